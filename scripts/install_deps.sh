#!/usr/bin/env bash
# Installs what VoxFuse needs to build and test on Debian 12. Idempotent: installs only what is missing.
# The CUDA toolkit is optional and not installed here (CMake uses it when nvcc is found). Packages
# named as arguments are installed too (scripts/fuzz.sh adds clang's). --tests adds the Python
# package's optional dependencies that its tests exercise (pyrealsense2, rerun-sdk; about 150 MB from
# PyPI) in a virtual environment, .venv-extras/, that the tests run in (without it they skip).
#   ./scripts/install_deps.sh [--tests] [PACKAGE...]
set -euo pipefail

with_test_extras=0
if [ "${1:-}" = "--tests" ]; then
  with_test_extras=1
  shift
fi

packages=(
  cmake ninja-build g++ pkg-config
  libeigen3-dev        # linear algebra (host side)
  libpng-dev libtiff-dev  # PNG and TIFF images
  libopencv-dev        # the video module (iPhone rgb.mp4), and the tests' reference codecs and undistortion
  libopenni2-dev       # optional: OpenNI2 cameras and .oni recordings (VOXFUSE_OPENNI2); pulls in its drivers
  libcli11-dev         # command-line parsing
  nlohmann-json3-dev   # the JSON reports (summary.json, timings.json, voxfuse_bench.json)
  libturbojpeg0-dev    # JPEG colour images, with damaged files reported rather than decoded grey
  zlib1g-dev           # checksums of map files
  libgtest-dev libgmock-dev
  liboctomap-dev       # optional: the OctoMap occupancy map (--occupancy)
  libceres-dev         # optional: the submaps' pose graph optimisation (mapping/PoseGraph.h)
  libglfw3-dev         # optional: the voxfuse_viewer demo
  xvfb xauth libgl1-mesa-dri   # the viewer's screenshot test under a virtual display
  pybind11-dev python3-dev python3-venv python3-numpy python3-pytest  # the Python package and its tests
  dpkg-dev             # dpkg-shlibdeps, for the Debian package's dependencies (cpack -G DEB)
  clang-format         # the layout check (scripts/check_format.sh, version 14 on Debian 12)
  "$@"
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all packages present"
else
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  echo "install_deps: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The Python tests run with the python3 found first on PATH (CMake builds the package for it). Debian's
# has numpy and pytest from the packages above; another one (pyenv, conda) gets them from PyPI.
if ! python3 -c "import numpy, pytest" 2>/dev/null; then
  echo "install_deps: installing numpy and pytest for $(command -v python3)"
  python3 -m pip install --quiet --disable-pip-version-check numpy pytest
fi

# The optional Python dependencies, for the tests of RealSense input and Rerun logging. The venv sees
# the interpreter's own packages (numpy, pytest); a failed download leaves those tests skipping.
if [ "$with_test_extras" = 1 ]; then
  extras="$(cd "$(dirname "$0")/.." && pwd)/.venv-extras"
  if [ -x "$extras/bin/python" ] && "$extras/bin/python" -c "import pyrealsense2, rerun" 2>/dev/null; then
    echo "install_deps: test extras present in $extras"
  else
    echo "install_deps: installing pyrealsense2 and rerun-sdk into $extras"
    if ! { python3 -m venv --system-site-packages "$extras" &&
           "$extras/bin/python" -m pip install --quiet --disable-pip-version-check pyrealsense2 rerun-sdk; }; then
      echo "install_deps: warning: the test extras could not be installed; their tests will skip" >&2
    fi
  fi
fi
