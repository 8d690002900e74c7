#!/usr/bin/env bash
# The README's picture of the Rerun viewer: a run of SEQ logged to an .rrd file (python -m voxfuse
# --rerun, with its blueprint), shown by Rerun's own viewer under a virtual X server with software
# Vulkan, and saved as PNG by the viewer's --screenshot-to.
#   scripts/rerun_screenshot.sh [SEQ] [OUT.png]    (default: ../shared/data/tum_fr3_teddy_200, docs/images/rerun_teddy.png)
# Needs: a build in ./build, rerun-sdk in .venv-extras (install_deps.sh --tests), and xvfb,
# mesa-vulkan-drivers and imagemagick (apt-get install).
set -euo pipefail
cd "$(dirname "$0")/.."
seq=${1:-../shared/data/tum_fr3_teddy_200}
out=${2:-docs/images/rerun_teddy.png}
python=.venv-extras/bin/python
for tool in xvfb-run convert; do
  command -v "$tool" >/dev/null || { echo "rerun_screenshot: needs $tool (apt-get install xvfb imagemagick mesa-vulkan-drivers)" >&2; exit 2; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
PYTHONPATH=build/python "$python" -m voxfuse "$seq" --out "$work/out" --rerun "$work/run.rrd" --rerun-mesh-every 0 2>/dev/null
# A home of its own: the viewer would otherwise restore the layout it saved for "voxfuse" last time.
# Its window is 1280x720 points (the guessed scale factor doubles its pixels), on a screen large enough
# that the pointer, at the screen's centre, is outside it and shows no tooltip.
HOME=$work XDG_DATA_HOME=$work XDG_CONFIG_HOME=$work XDG_RUNTIME_DIR=$work xvfb-run -a -s "-screen 0 3000x2000x24" \
  "$(dirname "$python")/rerun" "$work/run.rrd" --port 0 --window-size 1280x720 --screenshot-to "$work/shot.png" >"$work/viewer.log" 2>&1 ||
  { cat "$work/viewer.log" >&2; exit 1; }
convert "$work/shot.png" -resize 1280x -strip -define png:compression-level=9 "$out"
echo "rerun_screenshot: $out"
