#!/bin/sh
# Runs a test binary under umockdev's preload library. ASan insists on being first in the link
# order, which a preload breaks; the combination is fine (PLATFORM-NOTES), so tell ASan so.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"
exec umockdev-wrapper "$@"
