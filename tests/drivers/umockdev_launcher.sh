#!/bin/sh
# Runs a test binary under umockdev's preload library. ASan insists on being first in the link
# order, which a preload breaks; the combination is fine (PLATFORM-NOTES), so tell ASan so.
# Without umockdev the binary runs bare and its USB tests skip with a message.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"
# under TSan: races inside glib/umockdev (uninstrumented) are suppressed, ours are not
export TSAN_OPTIONS="${TSAN_OPTIONS:+$TSAN_OPTIONS:}suppressions=$(dirname "$0")/tsan-umockdev.supp"
command -v umockdev-wrapper >/dev/null 2>&1 || exec "$@"
exec umockdev-wrapper "$@"
