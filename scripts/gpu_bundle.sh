#!/usr/bin/env bash
# Builds, on this machine, what the GPU check needs on a lent GPU machine (x86-64, NVIDIA Hopper,
# sm_90; nvcc, CMake and Python there, but no Debian -dev packages and no package registry), and
# gathers it in gpu_bundle/ (git-ignored, under 64 MiB): the core library without image I/O, the
# cuda-labelled tests, voxfuse_bench, fallbacks for the C++ runtime libraries, gpu_check.sh with its
# summary and parity scripts, TUM fr3/teddy's 200 depth frames from ../shared/data as a depth pack
# (13 MiB; needs numpy and Pillow), and the CPU's results on that pack (reference/: poses, the bench
# JSON with its mesh counts, a sample of the mesh's vertices), made here by the bundle's own binary so
# that the lent window spends no time on CPU work.
#
#   ./scripts/gpu_bundle.sh            then, on the GPU machine, from the repository root:
#   ./gpu_bundle/gpu_check.sh          (carry gpu_bundle with the call)
set -euo pipefail
cd "$(dirname "$0")/.."
bundle=gpu_bundle
build=build-gpu-bundle
limit_mib=64

cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DVOXFUSE_CUDA=ON -DVOXFUSE_IO=OFF -DCMAKE_CUDA_ARCHITECTURES=90-real \
  -DCMAKE_DISABLE_FIND_PACKAGE_octomap=ON -DCMAKE_DISABLE_FIND_PACKAGE_Ceres=ON >/dev/null
cmake --build "$build" -j2 --target voxfuse_core_tests voxfuse_cuda_tests voxfuse_bench

rm -rf "$bundle"
mkdir -p "$bundle/bin" "$bundle/lib" "$bundle/fallback"
cp "$build/tests/voxfuse_core_tests" "$build/tests/voxfuse_cuda_tests" "$build/apps/voxfuse_bench" "$bundle/bin/"
cp -P "$build"/src/libvoxfuse_core.so* "$bundle/lib/"
# The GPU machine's own C++ runtime is used where it has one; these serve where it has not.
for lib in libgomp.so.1 libstdc++.so.6 libgcc_s.so.1 libz.so.1; do
  cp -L "$(g++ -print-file-name=$lib)" "$bundle/fallback/$lib"
done
strip --strip-unneeded "$bundle"/bin/* "$bundle"/lib/libvoxfuse_core.so.*.* 2>/dev/null || true
cp scripts/gpu_check.sh scripts/gpu_check_summary.py scripts/device_parity.py "$bundle/"
teddy=../shared/data/tum_fr3_teddy_200
if [ -d "$teddy" ]; then
  python3 scripts/make_depth_pack.py "$teddy" "$bundle/teddy_pack" --frames 200 --calib calib/tum_fr3.txt
  # The CPU reference: the options gpu_check.sh runs teddy_cuda with, on the CPU. The mesh (70 MB) is
  # carried as a sample of its vertices.
  mkdir -p "$bundle/reference"
  work=$(mktemp -d)
  LD_LIBRARY_PATH="$bundle/lib" "$bundle/bin/voxfuse_bench" "$bundle/teddy_pack" --device cpu --tracker ren --voxel s --mesh --repeats 1 \
    --json "$bundle/reference/teddy_cpu.json" --trajectory "$bundle/reference/teddy_cpu_trajectory.txt" --mesh-out "$work/mesh.ply" >/dev/null
  python3 scripts/device_parity.py --sample-mesh "$work/mesh.ply" "$bundle/reference/teddy_cpu_mesh_sample.ply"
  rm -rf "$work"
else
  echo "gpu_bundle: $teddy not found: the bundle has no real frames, the check runs on synthetic ones only" >&2
fi
git rev-parse --short HEAD >"$bundle/commit.txt" 2>/dev/null || echo unknown >"$bundle/commit.txt"

size_kib=$(du -sk "$bundle" | cut -f1)
echo "gpu_bundle: $bundle/ is $((size_kib / 1024)) MiB (limit ${limit_mib} MiB); commit $(cat "$bundle/commit.txt")"
if [ "$size_kib" -ge $((limit_mib * 1024)) ]; then
  echo "gpu_bundle: too large to carry" >&2
  exit 1
fi
