#!/usr/bin/env bash
# Installs what VoxFuse needs to build and test on Debian 12. Idempotent: installs only what is missing.
# The CUDA toolkit is optional and not installed here (CMake uses it when nvcc is found).
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config
  libeigen3-dev        # linear algebra (host side)
  libopencv-dev        # image codecs (PNG/JPEG)
  libcli11-dev         # command-line parsing
  libgtest-dev libgmock-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install_deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
