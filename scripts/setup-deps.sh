#!/usr/bin/env bash
# Installs the Debian 12 packages cmam needs to build, test and benchmark.
# Does nothing when everything is already present. Must run as root (or via sudo).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libembree-dev libtbb-dev libcli11-dev
  libpng-dev libjpeg62-turbo-dev libtiff-dev libopenexr-dev libstb-dev
  libgtest-dev libgmock-dev googletest libbenchmark-dev libopenimageio-dev
)
# With --test, also what the tests need beyond the build: Chromium opens the HTML report, and
# Clang builds the filtering library a second time and, with libFuzzer and the sanitizers'
# runtimes (libclang-rt-14-dev), the fuzz targets. With --fuzz, only what `make fuzz` needs.
case "${1:-}" in
  --test) packages+=(chromium clang libclang-rt-14-dev) ;;
  --fuzz) packages+=(clang libclang-rt-14-dev) ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  exit 0
fi
echo "cmam: installing missing packages: ${missing[*]}" >&2
SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "cmam: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
