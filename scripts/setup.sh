#!/usr/bin/env bash
# Install everything the project needs on a fresh Debian machine:
# the cross toolchains and simulators (apt, needs root or sudo) and the
# Python package with its `dev` extra (editable, so the CFFI extensions are
# built from this tree): everything a test, a benchmark or an invoke task
# imports (pyproject.toml; tests/test_dependencies.py checks it).
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(
  gcc clang libclang-rt-14-dev make cmake pkg-config  # host builds, sanitizers, fuzzing
  clang-format                                        # C style (.clang-format), checked by the tests
  gcc-arm-none-eabi libnewlib-arm-none-eabi           # ARMv4T bare metal (semihosting)
  gcc-arm-linux-gnueabi libc6-dev-armel-cross         # ARMv4T embedded Linux (armel)
  gcc-arm-linux-gnueabihf libc6-dev-armhf-cross       # other Linux targets
  gcc-aarch64-linux-gnu libc6-dev-arm64-cross
  qemu-user                                           # qemu-arm -cpu ti925t, qemu-aarch64
  sdcc sdcc-ucsim                                     # AT89S51 firmware and the s51 simulator
  socat                                               # pseudo-terminal pairs for UART tests
  gpsd gpsd-clients libgps-dev                        # attitude-rx --gnss gpsd (libgps) and its tests (gpsfake)
  chromium                                            # attitude view's browser tests (driven by Playwright;
                                                      # its own browser download is not used)
)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup: installing Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  # with recommends: the cross compilers recommend their C libraries, which we need
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

PY=${PYTHON:-python3}
echo "setup: installing attitude_c (editable) with the dev extra (tests, benchmarks, tasks, linters)"
$PY -m pip install -q --upgrade pip >/dev/null 2>&1 || true
$PY -m pip install -q -e ".[dev]"
