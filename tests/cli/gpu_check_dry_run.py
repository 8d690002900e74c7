#!/usr/bin/env python3
"""scripts/gpu_check.sh on a machine without a GPU, as it will run on a lent one, so that a lent window
is never the first run of the script:

1. the real bundle layout with this build's binaries: preflight, ldd checks, the CUDA probe, the
   verdict `GPU CHECK: NO-GPU`, exit 2, every step named as skipped, the summary in OUT, in seconds;
2. a bundle whose test binary pretends the probe passed and then hangs: the step is cut at the
   deadline (timeout -k), every later step is skipped for time and named, verdict FAIL, exit 1;
3. the same, killed with SIGTERM mid-step: the trap still prints the summary and a FAIL verdict
   that says it was interrupted, and the hung step does not outlive the script;
4. a bundle whose cuda tests all skip (the probe passing): NO-GPU, not PASS.

    gpu_check_dry_run.py --script scripts/gpu_check.sh --summary scripts/gpu_check_summary.py
                         --build BUILD_DIR --work DIR"""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import time

FAILURES = []


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what)
    if not condition:
        FAILURES.append(what)


def make_bundle(root, args, cuda_tests_stub=None):
    """A bundle as gpu_bundle.sh lays it out: bin/, lib/, fallback/, the scripts, commit.txt."""
    shutil.rmtree(root, ignore_errors=True)
    for d in ("bin", "lib", "fallback"):
        os.makedirs(os.path.join(root, d))
    for name, rel in (("voxfuse_core_tests", "tests/voxfuse_core_tests"), ("voxfuse_cuda_tests", "tests/voxfuse_cuda_tests"),
                      ("voxfuse_bench", "apps/voxfuse_bench")):
        target = os.path.join(root, "bin", name)
        if name == "voxfuse_cuda_tests" and cuda_tests_stub is not None:
            with open(target, "w") as f:
                f.write("#!/bin/sh\n" + cuda_tests_stub)
            os.chmod(target, 0o755)
        elif os.path.exists(os.path.join(args.build, rel)):
            os.symlink(os.path.abspath(os.path.join(args.build, rel)), target)
    for lib in os.listdir(os.path.join(args.build, "src")):
        if lib.startswith("libvoxfuse_core.so"):
            os.symlink(os.path.abspath(os.path.join(args.build, "src", lib)), os.path.join(root, "lib", lib))
    shutil.copy(args.script, os.path.join(root, "gpu_check.sh"))
    shutil.copy(args.summary, os.path.join(root, "gpu_check_summary.py"))
    with open(os.path.join(root, "commit.txt"), "w") as f:
        f.write("dry-run\n")


def run(bundle, out, deadline, kill_after=None):
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ, OUT=out)
    started = time.monotonic()
    proc = subprocess.Popen(["bash", os.path.join(bundle, "gpu_check.sh"), "--deadline", str(deadline)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    if kill_after is not None:
        time.sleep(kill_after)
        proc.send_signal(signal.SIGTERM)  # the script alone, as a supervisor would
    try:
        text, _ = proc.communicate(timeout=90)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        text, _ = proc.communicate()
        text += "\n(dry run: the script did not end within 90 s)"
    return proc.returncode, text, time.monotonic() - started


def verdict_of(text):
    lines = [l for l in text.splitlines() if l.startswith("GPU CHECK: ")]
    return lines[-1] if lines else ""


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--script", required=True)
    parser.add_argument("--summary", required=True)
    parser.add_argument("--build", required=True)
    parser.add_argument("--work", required=True)
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    bundle, out = os.path.join(args.work, "bundle"), os.path.join(args.work, "out")
    steps = ("cuda_tests", "engine_cuda_tests", "teddy_cuda", "bench_cuda_tracked", "bench_cuda_hash", "bench_cuda_dense",
             "memcheck_cuda_tests", "memcheck_engine_tests")

    # 1. This build, no GPU.
    make_bundle(bundle, args)
    rc, text, secs = run(bundle, out, 420)
    print(text)
    check(rc == 2, f"no GPU: exit 2 (got {rc})")
    check(verdict_of(text).startswith("GPU CHECK: NO-GPU ("), "no GPU: one NO-GPU verdict line: " + verdict_of(text))
    check(secs < 60, f"no GPU: ends in seconds ({secs:.1f} s)")
    check("libraries: every carried binary resolves" in text, "no GPU: the carried binaries were checked with ldd")
    check("glibc:" in text, "no GPU: the preflight names glibc")
    status = open(os.path.join(out, "status.txt")).read() if os.path.exists(os.path.join(out, "status.txt")) else ""
    check(all(f"{s} skipped" in status for s in steps), "no GPU: every step is named as skipped in status.txt")
    check(os.path.exists(os.path.join(out, "verdict.txt")) and open(os.path.join(out, "verdict.txt")).read().startswith("GPU CHECK: NO-GPU"),
          "no GPU: the verdict is written to OUT")
    check("==== VoxFuse GPU check summary" in open(os.path.join(out, "summary.txt")).read(), "no GPU: the summary is written to OUT")

    # 2. A GPU that passes the probe, then a test binary that hangs: cut at the deadline, the rest skipped.
    hang = ('case "$*" in *ReadAndWriteOneElement*) echo "[  PASSED  ] 1 test."; exit 0 ;; esac\n'
            'sleep 117\n')  # a duration of its own, to look for below
    make_bundle(bundle, args, cuda_tests_stub=hang)
    # 33 s: the cuda tests' least useful time (30 s) fits, the next step's (20 s) then does not.
    rc, text, secs = run(bundle, out, 33)
    print(text)
    check(rc == 1, f"hung step: exit 1 (got {rc})")
    v = verdict_of(text)
    check(v.startswith("GPU CHECK: FAIL (failed: cuda_tests (timed-out-after-"), "hung step: FAIL names the step cut at the deadline: " + v)
    check("skipped" in text and "engine_cuda_tests: skipped (needs at least" in text, "hung step: later steps are skipped for time, by name")
    check(secs < 50, f"hung step: the deadline holds ({secs:.1f} s for a 33 s deadline)")

    # 3. Killed mid-step: the trap reports, and the step's process is gone.
    rc, text, secs = run(bundle, out, 300, kill_after=3)
    print(text)
    v = verdict_of(text)
    check(rc == 1 and v.startswith("GPU CHECK: FAIL (interrupted by SIGTERM"), f"SIGTERM: FAIL, interrupted (exit {rc}): {v}")
    check("==== VoxFuse GPU check summary" in text, "SIGTERM: the summary is printed")
    check(secs < 30, f"SIGTERM: answered at once, not after the step's limit ({secs:.1f} s)")
    time.sleep(0.5)
    leftover = subprocess.run(["pgrep", "-f", os.path.join(bundle, "bin", "voxfuse_cuda_tests") + "|sleep 117"], capture_output=True,
                              text=True).stdout
    check(leftover.strip() == "", "SIGTERM: no step process outlives the script")

    # 4. Every cuda test skipped although the probe passed: NO-GPU, never PASS.
    skip_all = ('case "$*" in *ReadAndWriteOneElement*) echo "[  PASSED  ] 1 test."; exit 0 ;; esac\n'
                'for a in "$@"; do case "$a" in --gtest_output=xml:*) f=${a#--gtest_output=xml:};\n'
                'printf \'<?xml version="1.0"?>\\n<testsuites tests="2">\\n<testsuite name="S" tests="2">\\n'
                '<testcase name="a" status="run" result="skipped" classname="S">\\n<skipped message="no GPU"/>\\n</testcase>\\n'
                '<testcase name="b" status="run" result="skipped" classname="S">\\n<skipped message="no GPU"/>\\n</testcase>\\n'
                '</testsuite>\\n</testsuites>\\n\' > "$f";; esac; done\nexit 0\n')
    make_bundle(bundle, args, cuda_tests_stub=skip_all)
    rc, text, secs = run(bundle, out, 120)
    print(text)
    v = verdict_of(text)
    check(rc == 2 and v.startswith("GPU CHECK: NO-GPU (every one of the"), f"all skipped: NO-GPU (exit {rc}): {v}")

    print("gpu_check dry run: " + ("PASS" if not FAILURES else f"FAIL ({len(FAILURES)} checks)"))
    sys.exit(1 if FAILURES else 0)


if __name__ == "__main__":
    main()
