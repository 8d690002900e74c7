#!/usr/bin/env bash
# What a new Python user does, checked: `pip install .` into a fresh virtual environment, then the
# package's tests against the installed copy (not the build tree). Needs scripts/install_deps.sh
# first and PyPI (for scikit-build-core and pybind11 in pip's isolated build environment).
#
#   ./scripts/check_python_install.sh        (from anywhere; uses a temporary folder)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python=${PYTHON:-python3}
# System site packages: numpy and pytest from Debian (or the interpreter's own) serve the venv.
"$python" -m venv --system-site-packages "$work/venv"
. "$work/venv/bin/activate"
start=$(date +%s)
CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-2} pip install --quiet --disable-pip-version-check "$repo"
echo "check_python_install: pip install . took $(( $(date +%s) - start )) s"
python -c "import numpy, pytest" 2>/dev/null || pip install --quiet --disable-pip-version-check numpy pytest
cd "$work"  # away from the checkout: the installed package is the one imported
python -c "import voxfuse; print('check_python_install: voxfuse from', voxfuse.__file__, '(CUDA', 'built)' if voxfuse.built_with_cuda() else 'not built)')"
python -m pytest -q -p no:cacheprovider "$repo/python/tests"
