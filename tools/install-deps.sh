#!/usr/bin/env bash
# Installs the Debian 12 packages vitreo builds, tests and runs with. Idempotent: it installs only
# what is missing, so a machine that has everything pays nothing. Needs root (or sudo).
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git
  # core
  libeigen3-dev libfcl-dev libccd-dev liboctomap-dev
  # rig: rendering, telemetry, USB, config, CLI, logging, images
  libegl-dev libegl-mesa0 libgles-dev libgl1-mesa-dri libgbm-dev libgl-dev libdrm-dev
  liblcm-dev liblcm-bin
  libusb-1.0-0-dev
  libtomlplusplus-dev libcli11-dev libspdlog-dev libfmt-dev libpng-dev
  # the session report (rig/report): Chart.js inlined into the page at build time, the survey
  # form's JSON read with nlohmann-json; headless
  # Chromium opens the page in its tests
  libjs-chart.js chromium nlohmann-json3-dev
  # recordings: the running CRC-32 of their checksum blocks
  zlib1g-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # the solver benchmark times Bullet's btSoftBody beside vitreo's step (tests/core/bullet_softbody_bench.cpp)
  libbullet-dev
  umockdev libumockdev-dev can-utils iproute2 util-linux
  # the install tests: systemd-analyze, -sysusers, -tmpfiles check the unit and snippets; udevadm
  # runs the udev rules; strace lists the system calls the unit's sandbox must allow
  systemd udev strace
  # SocketCAN and KMS display tests run inside a small qemu VM (the host kernel has neither)
  qemu-system-x86 linux-image-amd64 busybox-static cpio
  # protocol fuzz targets: clang's libFuzzer (GCC has none)
  clang libclang-rt-14-dev
  # the protocol is also compiled for Cortex-M in the tests (the firmware's target)
  gcc-arm-none-eabi
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
