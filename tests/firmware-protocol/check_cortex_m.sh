#!/usr/bin/env bash
# Compiles the protocol for Cortex-M0+ (no FPU, no unaligned access) and Cortex-M4F with the ARM
# embedded toolchain, freestanding, warnings as errors, and reports the code size. Skips (77)
# when arm-none-eabi-gcc is not installed.
set -eu
src=${1:?usage: check_cortex_m.sh <firmware-protocol dir>}
cc=$(command -v arm-none-eabi-gcc || true)
[ -n "$cc" ] || { echo "SKIP: arm-none-eabi-gcc not installed (apt-get install gcc-arm-none-eabi)"; exit 77; }
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
for cpu in "cortex-m0plus" "cortex-m4 -mfloat-abi=hard -mfpu=fpv4-sp-d16"; do
  for f in vp_codec vp_framing; do
    $cc -mcpu=$cpu -mthumb -Os -std=c99 -ffreestanding -nostdinc -isystem "$src/freestanding-include" \
        -isystem "$($cc -print-file-name=include)" -I"$src/.." -Wall -Wextra -Wpedantic -Wconversion -Werror \
        -ffunction-sections -c "$src/$f.c" -o "$out/$f.o"
  done
  # libgcc's helpers (__aeabi_* soft-float on the M0+, __gnu_thumb1_case_* switch tables) are the
  # compiler's own runtime, present in every freestanding toolchain; anything else would be libc
  undef=$(arm-none-eabi-nm -u "$out"/*.o | awk '{print $2}' | sort -u |
          grep -vxE 'memcpy|memset|vp_[a-z0-9_]+|__aeabi_[a-z0-9]+|__gnu_thumb1_case_[a-z]+' || true)
  [ -z "$undef" ] || { echo "FAIL: $cpu build needs: $undef"; exit 1; }
  echo "${cpu%% *}: $(arm-none-eabi-size -t "$out"/*.o | awk 'END{print $1 " B text, " $2 " B data, " $3 " B bss"}')"
done
