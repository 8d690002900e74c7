#!/usr/bin/env python3
"""Side-by-side speed of two VoxFuse builds: runs their voxfuse_bench alternately on the same frames and
prints per-stage medians and the ratio new/old.

This machine's speed drifts by tens of percent over minutes, so only runs taken side by side compare:
each round runs both builds, in ABBA order (old, new, new, old, ...) so that a drift within a round
weighs on both alike. A stage's time per build is the median, over rounds, of voxfuse_bench's per-run
median.

  scripts/compare_builds.py --old main --new build                         # a git revision vs a build folder
  scripts/compare_builds.py --old build-old --new build --rounds 4 -- ../shared/data/tum_fr3_teddy_200 --voxel s_rgb

--old/--new take a build folder (one holding apps/voxfuse_bench) or a git revision, which is built
(Release, CPU only, no tests) in build-compare/<commit>/ from a worktree of this checkout and kept
for the next comparison. Everything after `--` goes to voxfuse_bench (default: teddy, s_rgb voxels,
the CLI's defaults otherwise).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_BENCH_ARGS = [os.path.join(REPO, "..", "shared", "data", "tum_fr3_teddy_200"), "--voxel", "s_rgb"]


def bench_of(build_dir):
    return os.path.join(build_dir, "apps", "voxfuse_bench")


def build_revision(rev):
    """Builds revision `rev` in build-compare/<commit>/ (once) and returns that build folder."""
    commit = subprocess.run(["git", "-C", REPO, "rev-parse", "--verify", rev + "^{commit}"], check=True, capture_output=True,
                            text=True).stdout.strip()
    root = os.path.join(REPO, "build-compare", commit[:12])
    build = os.path.join(root, "build")
    if os.path.exists(bench_of(build)):
        return build
    source = os.path.join(root, "src")
    if not os.path.exists(source):
        subprocess.run(["git", "-C", REPO, "worktree", "add", "--detach", source, commit], check=True)
    print(f"compare_builds: building {rev} ({commit[:12]}) in {build}", file=sys.stderr)
    subprocess.run(["cmake", "-S", source, "-B", build, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release", "-DVOXFUSE_CUDA=OFF",
                    "-DVOXFUSE_PYTHON=OFF", "-DVOXFUSE_BUILD_TESTS=OFF"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", build, "-j2", "--target", "voxfuse_bench"], check=True, stdout=subprocess.DEVNULL)
    return build


def resolve(what):
    if os.path.exists(bench_of(what)):
        return os.path.abspath(what)
    if os.path.isdir(what):
        sys.exit(f"compare_builds: {what} is a folder without apps/voxfuse_bench")
    return build_revision(what)


def run_bench(build, bench_args, env=None, timings=False):
    """One voxfuse_bench run: its JSON report, and with `timings` also its per-frame timings (a pair)."""
    with tempfile.TemporaryDirectory() as tmp:
        report, per_frame = os.path.join(tmp, "bench.json"), os.path.join(tmp, "timings.json")
        extra = ["--timings", per_frame] if timings else []
        done = subprocess.run([bench_of(build), *bench_args, "--json", report, *extra], capture_output=True, text=True, env=env)
        if done.returncode != 0:
            sys.exit(f"{os.path.basename(sys.argv[0])}: {bench_of(build)} failed ({done.returncode}):\n{done.stdout}{done.stderr}")
        with open(report) as f:
            result = json.load(f)
        if not timings:
            return result
        with open(per_frame) as f:
            return result, json.load(f)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--old", required=True, help="build folder or git revision")
    parser.add_argument("--new", required=True, help="build folder or git revision")
    parser.add_argument("--rounds", type=int, default=3, help="rounds; each runs both builds (default 3)")
    parser.add_argument("--json", help="also write the comparison here")
    parser.add_argument("bench_args", nargs="*", help="arguments for voxfuse_bench (after --)")
    args = parser.parse_args()
    if args.rounds < 1:
        sys.exit("compare_builds: --rounds must be at least 1")
    bench_args = args.bench_args or DEFAULT_BENCH_ARGS
    builds = {"old": resolve(args.old), "new": resolve(args.new)}

    runs = {"old": [], "new": []}
    for r in range(args.rounds):
        order = ["old", "new"] if r % 2 == 0 else ["new", "old"]
        for which in order:
            report = run_bench(builds[which], bench_args)
            runs[which].append(report)
            total = report["stages"]["total"]["median_ms"]
            print(f"  round {r + 1}: {which} total {total:.2f} ms", file=sys.stderr)

    def median_over_runs(which, stage):
        values = [r["stages"][stage]["median_ms"] for r in runs[which] if stage in r["stages"]]
        return statistics.median(values) if values else None

    stages = [s for s in runs["new"][0]["stages"] if s in runs["old"][0]["stages"]]
    result = {"old": builds["old"], "new": builds["new"], "rounds": args.rounds, "bench_args": bench_args, "stages": {}}
    print(f"old: {builds['old']}\nnew: {builds['new']}\nvoxfuse_bench {' '.join(bench_args)}; {args.rounds} rounds, ABBA")
    print(f"{'stage':<12}{'old ms':>10}{'new ms':>10}{'new/old':>9}")
    for stage in stages:
        old, new = median_over_runs("old", stage), median_over_runs("new", stage)
        ratio = new / old if old else float("nan")
        result["stages"][stage] = {"old_ms": old, "new_ms": new, "ratio": ratio}
        print(f"{stage:<12}{old:>10.2f}{new:>10.2f}{ratio:>9.3f}")
    for key, unit, scale in [("ate_rmse_m", "mm", 1000.0), ("peak_rss_mb", "MB", 1.0)]:
        values = {w: [r[key] for r in runs[w] if key in r] for w in runs}
        if values["old"] and values["new"]:
            old, new = statistics.median(values["old"]) * scale, statistics.median(values["new"]) * scale
            result[key] = {"old": old / scale, "new": new / scale}
            print(f"{key:<12}{old:>10.2f}{new:>10.2f}  {unit}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=2)


if __name__ == "__main__":
    main()
