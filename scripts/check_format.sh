#!/usr/bin/env bash
# Fails when a tracked C++ or CUDA file differs from what clang-format makes of it (.clang-format),
# naming each file; --fix rewrites them instead. The layout is clang-format 14's (Debian 12's), so
# another major version, which lays out some constructs differently, skips with exit 77 (CTest's
# "skipped") rather than fail on code that is formatted.
#   scripts/check_format.sh [--fix]
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v clang-format >/dev/null 2>&1; then
  echo "check_format: clang-format not found (scripts/install_deps.sh installs it)"
  exit 77
fi
major=$(clang-format --version | sed -n 's/.*clang-format version \([0-9]*\).*/\1/p')
if [ "$major" != 14 ]; then
  echo "check_format: clang-format $major here; the tree is laid out by clang-format 14 (Debian 12)"
  exit 77
fi
files=$(git ls-files '*.h' '*.hpp' '*.cpp' '*.cu' '*.cuh' | grep -v '^tests/fuzz/corpus/' || true)
if [ "${1:-}" = --fix ]; then
  echo "$files" | xargs clang-format -i
  exit 0
fi
bad=()
for f in $files; do
  clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "check_format: ${#bad[@]} files are not laid out as .clang-format says (scripts/check_format.sh --fix):"
  printf '  %s\n' "${bad[@]}"
  exit 1
fi
echo "check_format: $(echo "$files" | wc -l) files formatted"
