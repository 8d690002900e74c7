#!/usr/bin/env python3
"""How a frame's time scales with the threads and with what the camera sees.

Runs voxfuse_bench alternately with 1 and 2 CPU threads (ABBA over --rounds, so machine drift hits
both alike), each run writing its per-frame stage times (--timings), and prints:
  - each stage's median ms with 1 and with 2 threads, and the speed-up;
  - the frames split into thirds by the number of visible blocks: median blocks and stage ms of the
    third that sees least and of the third that sees most, and a least-squares line of the whole
    frame's ms against the visible blocks, per thread count.

    scripts/scaling_report.py [--bin BUILD_OR_REVISION] [--rounds 2] [--json FILE] [-- BENCH ARGUMENTS...]

--bin and the bench arguments are as scripts/compare_builds.py takes them (default: build/, and teddy
at the default settings).
"""

import argparse
import json
import os
import statistics
import sys

from compare_builds import DEFAULT_BENCH_ARGS, REPO, resolve, run_bench

WARMUP = 3  # frames left out, as voxfuse_bench's default --warmup


def run(build, bench_args, threads):
    """The per-frame timings of one run with `threads` CPU threads."""
    env = dict(os.environ, VOXFUSE_NUM_THREADS=str(threads))
    return run_bench(build, [*bench_args, "--warmup", str(WARMUP)], env=env, timings=True)[1]


def fit_line(xs, ys):
    """Least-squares y = a + b x; (a, b)."""
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else 0.0
    return my - b * mx, b


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", default=os.path.join(REPO, "build"), help="build folder holding apps/voxfuse_bench, or a git revision")
    parser.add_argument("--rounds", type=int, default=2, help="runs per thread count (ABBA)")
    parser.add_argument("--json", help="also write the report here")
    parser.add_argument("bench_args", nargs="*", help="arguments for voxfuse_bench (after --)")
    args = parser.parse_args()
    if args.rounds < 1:
        sys.exit("scaling_report: --rounds must be at least 1")
    build = resolve(args.bin)
    bench_args = args.bench_args or DEFAULT_BENCH_ARGS

    # frames[threads][frame index] = list over rounds of that frame's record
    frames = {1: {}, 2: {}}
    stages = []
    for r in range(args.rounds):
        for threads in ((1, 2) if r % 2 == 0 else (2, 1)):
            t = run(build, bench_args, threads)
            stages = stages or [s for s in t["median_ms"] if s != "total"] + ["total"]
            for f in t["frames"][WARMUP:]:
                frames[threads].setdefault(f["index"], []).append(f)
            print(f"round {r + 1}: {threads} thread(s) done", file=sys.stderr)

    def per_frame(threads, key):
        """The frame's median over rounds of `key`, by frame index."""
        return {i: statistics.median(f.get(key, 0.0) for f in runs) for i, runs in frames[threads].items()}

    common = sorted(set(frames[1]) & set(frames[2]))
    if len(common) < 3:
        sys.exit("scaling_report: fewer than 3 frames after the warm-up")
    report = {"bench_args": bench_args, "rounds": args.rounds, "frames": len(common), "stages": {}, "by_visible_blocks": {}}

    print(f"voxfuse_bench {' '.join(bench_args)}; {args.rounds} rounds per thread count, ABBA; {len(common)} frames")
    print(f"\n{'stage':<12} {'1 thread ms':>12} {'2 threads ms':>13} {'speed-up':>9}")
    for s in stages:
        one, two = per_frame(1, s), per_frame(2, s)
        m1, m2 = statistics.median(one[i] for i in common), statistics.median(two[i] for i in common)
        report["stages"][s] = {"1": m1, "2": m2, "speedup": m1 / m2 if m2 > 0 else None}
        print(f"{s:<12} {m1:12.2f} {m2:13.2f} {m1 / m2 if m2 > 0 else float('nan'):9.2f}")

    blocks = per_frame(2, "visible_blocks")
    if not any(blocks.values()):
        print("\nno visible blocks reported (not a hash index): no split by view")
    else:
        ordered = sorted(common, key=lambda i: blocks[i])
        third = max(1, len(ordered) // 3)
        groups = {"least": ordered[:third], "most": ordered[-third:]}
        print(f"\nframes by visible blocks (thirds of {len(ordered)}): median ms")
        print(f"{'view':<6} {'blocks':>7} " + " ".join(f"{s + ' ' + str(t) + 't':>14}" for s in ("total",) for t in (1, 2)) +
              " " + " ".join(f"{s:>10}" for s in stages if s != "total"))
        for name, idx in groups.items():
            row = {"visible_blocks": statistics.median(blocks[i] for i in idx)}
            for t in (1, 2):
                for s in stages:
                    row[f"{s}_{t}"] = statistics.median(per_frame(t, s)[i] for i in idx)
            report["by_visible_blocks"][name] = row
            print(f"{name:<6} {row['visible_blocks']:7.0f} {row['total_1']:14.2f} {row['total_2']:14.2f} " +
                  " ".join(f"{row[s + '_2']:10.2f}" for s in stages if s != "total"))
        print("(stage columns: 2 threads)")
        for t in (1, 2):
            totals = per_frame(t, "total")
            a, b = fit_line([blocks[i] / 1000.0 for i in common], [totals[i] for i in common])
            report[f"total_ms_per_1000_blocks_{t}"] = b
            report[f"total_ms_at_no_blocks_{t}"] = a
            print(f"{t} thread(s): total ms ~ {a:.1f} + {b:.2f} per 1000 visible blocks")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=2)


if __name__ == "__main__":
    main()
