#!/bin/bash
# KMS scan-out test: boots the VM with qemu's bochs-display, runs the static kms_vm_test in it (which
# presents frames and asks for a screendump), then checks the dump on the host.
# Usage: run_kms_vm_test.sh <kms_vm_test> <check_screendump>   Exit 125 = VM unavailable (skip).
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dump=$(mktemp "${TMPDIR:-/tmp}/vitreo-kms-dump.XXXXXX.ppm")
trap 'rm -f "$dump"' EXIT
VM_MODULES="bochs" SCREENDUMP="$dump" "$here/../../../vm/run-in-vm.sh" "$1"
rc=$?
[ $rc = 0 ] || exit $rc
[ -s "$dump" ] || { echo "FAIL: qemu wrote no screendump"; exit 1; }
"$2" "$dump"
