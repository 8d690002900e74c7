#!/usr/bin/env python3
"""Runs voxfuse and voxfuse_bench on malformed inputs, every option and parser, signals, a full disk,
read-only and misnamed folders, and paths that are not UTF-8, and says for each what the programs
answered: ok (an error naming what and why, or the expected success), unclear (an error that does not
say it), silent (accepted: exit 0), crash (a signal, an abort, a sanitizer report) or hang.

    scripts/bad_inputs.py [--bin build] [--compare OTHER_BUILD] [--table FILE] [--only WORD] [--quick]

--bin is a build folder (apps/voxfuse, apps/voxfuse_bench and apps/synth/voxfuse_synth in it) or a
folder holding the three programs (and their libraries). With --compare, each input also runs with
the other build's programs and the table shows both answers. --quick runs the signals, the output
paths and every fifth other case (the test suite's cli.bad_inputs). Exits 1 when an answer is not ok.
A full disk and a read-only folder need `mount -t tmpfs` (root); without it those cases are skipped.
"""

import argparse
import json
import os
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOM = os.path.join(ROOT, "data", "synthetic_room")
ONI = os.path.join(ROOT, "..", "shared", "data", "oni", "test.oni")


class Programs:
    def __init__(self, folder):
        folder = os.path.abspath(folder)
        def find(*names):
            for n in names:
                p = os.path.join(folder, n)
                if os.path.isfile(p):
                    return p
            sys.exit(f"bad_inputs: no {names[-1]} in {folder}")
        self.voxfuse = find("apps/voxfuse", "voxfuse")
        self.bench = find("apps/voxfuse_bench", "voxfuse_bench")
        self.synth = find("apps/synth/voxfuse_synth", "voxfuse_synth")
        self.env = dict(os.environ, LD_LIBRARY_PATH=folder + ":" + os.environ.get("LD_LIBRARY_PATH", ""))
        # The Python package as the build assembled it (<build>/python/voxfuse), if it did.
        self.python_package = os.path.join(folder, "python") if os.path.isdir(os.path.join(folder, "python", "voxfuse")) else None
        # AddressSanitizer reserves terabytes of address space: no limit for such a build.
        ldd = subprocess.run(["ldd", self.voxfuse], capture_output=True, text=True, env=self.env).stdout
        self.limit = limit_memory if "libasan" not in ldd else None


# ---------------------------------------------------------------------------------------------
# Files

def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def read(path):
    with open(path, "rb") as f:
        return f.read()


def png(width, height, bit_depth, color_type, rows):
    """A PNG from rows of raw bytes (no filtering)."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + r for r in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, color_type, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def depth_png(width, height, value=1000):
    return png(width, height, 16, 0, [struct.pack(">%dH" % width, *([value] * width)) for _ in range(height)])


GOOD_CALIB = ("64 48\n50 50\n31.5 23.5\n\n64 48\n50 50\n31.5 23.5\n\n"
              "1 0 0 0\n0 1 0 0\n0 0 1 0\n\naffine 0.0002 0\n")


def calib_with(line_number, text):
    lines = GOOD_CALIB.split("\n")
    lines[line_number - 1] = text
    return "\n".join(lines)


class Fixtures:
    """Small sequences made once per run with voxfuse_synth (the build under test's)."""

    def __init__(self, programs, work):
        self.work = work
        self.tum = os.path.join(work, "tum")
        self.ppm = os.path.join(work, "ppm")
        for out, fmt in ((self.tum, "tum"), (self.ppm, "ppm")):
            subprocess.run([programs.synth, "--out", out, "--frames", "4", "--width", "64", "--height", "48", "--format", fmt],
                           check=True, capture_output=True, env=programs.env)
        self.map = os.path.join(work, "room.vfm")
        subprocess.run([programs.voxfuse, self.tum, "--voxel", "s", "--frames", "2", "--render-every", "0", "--out",
                        os.path.join(work, "map_run"), "--save-map", self.map], check=True, capture_output=True, env=programs.env)

    def copy_tum(self, case_dir):
        dst = os.path.join(case_dir, "tum")
        shutil.copytree(self.tum, dst)
        return dst

    def copy_ppm(self, case_dir):
        dst = os.path.join(case_dir, "ppm")
        shutil.copytree(self.ppm, dst)
        return dst

    def frame_folder(self, case_dir):
        dst = os.path.join(case_dir, "frames")
        rgb = sorted(os.listdir(os.path.join(self.tum, "rgb")))
        for i, name in enumerate(rgb[:3]):
            write(os.path.join(dst, "frame-%06d.depth.png" % i), depth_png(64, 48))
            shutil.copy(os.path.join(self.tum, "rgb", name), os.path.join(dst, "frame-%06d.color.jpg" % i))
            write(os.path.join(dst, "frame-%06d.pose.txt" % i), "1 0 0 0\n0 1 0 0\n0 0 1 %g\n0 0 0 1\n" % (0.01 * i))
        write(os.path.join(dst, "intrinsics.K.txt"), "50 0 31.5\n0 50 23.5\n0 0 1\n")
        return dst


# ---------------------------------------------------------------------------------------------
# Cases: what to run and what a good answer contains

class Case:
    def __init__(self, category, what, argv, expect=(), ok_exit=False, setup=None, check=None, program="voxfuse",
                 interrupt=None, needs_mount=False, env=None):
        self.category, self.what, self.argv, self.expect = category, what, argv, list(expect)
        self.ok_exit, self.setup, self.check, self.program = ok_exit, setup, check, program
        self.interrupt, self.needs_mount, self.env = interrupt, needs_mount, env or {}


def cases():
    c = []
    TUM, OUT = "{tum}", "{out}"
    base = [TUM, "--frames", "2", "--render-every", "0", "--out", OUT]

    def opt(option, value, *expect, extra=()):
        c.append(Case("option", f"{option} {value}".strip(), base + list(extra) + [option] + value.split(),
                      [option] + list(expect)))

    # ---- every numeric option: NaN, infinities, floats that are infinite as floats, negatives, words
    for option, values in {
        "--voxel-size": ["nan", "inf", "1e39", "-0.01", "0", "abc", "2", "1e-50"],
        "--mu": ["nan", "1e39", "-1", "0"],
        "--min-depth": ["nan", "-1", "inf", "1e39"],
        "--max-depth": ["nan", "-1", "0", "1e39"],
        "--cloud-voxel": ["nan", "0", "1e-12", "-1"],
        "--occupancy": ["nan", "0", "1e-9", "1e39"],
        "--tracker-max-distance": ["nan", "-1", "0"],
        "--relocalise-max-speed": ["nan", "-1", "x"],
        "--relocalise-min-color-correlation": ["nan", "2", "-1.5"],
        "--relocalise-min-colour-correlation": ["nan"],  # the former spelling, checked alike
        "--depth-gap-tolerance": ["nan", "-1", "1"],
    }.items():
        for v in values:
            opt(option, v, v)
    for option, values in {
        "--max-weight": ["0", "256", "-1", "x"],
        "--frames": ["-1", "x", "99999999999"],
        "--skip": ["-1"],
        "--render-every": ["-1", "99999999999"],
        "--active-blocks": ["-5", "2147483647"],
        "--relocalise-candidates": ["0", "100000"],
        "--max-blocks": ["-1", "999999999"],
        "--hash-buckets": ["0", "-1"],
        "--hash-excess": ["-1"],
        "--tracker-iterations": ["0", "100000", "x"],
        "--exclude-classes": ["70000", "-1", "a"],
        "--min-confidence": ["3", "-1"],
        "--label-ignore": ["-2", "70000"],
    }.items():
        for v in values:
            opt(option, v, v)
    opt("--swap-blocks-per-frame", "0", "0", extra=["--swap"])
    opt("--volume-size", "0 0 0", "0", extra=["--index", "dense"])
    opt("--volume-size", "-1 1 1", "-1", extra=["--index", "dense"])
    opt("--volume-size", "100000 1 1", "100000", extra=["--index", "dense"])
    opt("--volume-offset", "x 0 0", "x", extra=["--index", "dense"])
    for option, value in [("--voxel", "xyz"), ("--index", "sparse"), ("--device", "gpu"), ("--poses", "gt"), ("--tracker", "orb"),
                          ("--label-match", "foo"), ("--label-update", "bar")]:
        opt(option, value, value)
    opt("--tracker-levels", "xyz", "xyz", "level types")
    opt("--tracker-levels", "rrrrrrrrrr", "1 to 8 levels")

    # ---- options that do not fit together, or settings too large to honour
    def combo(what, args, *expect):
        c.append(Case("combination", what, base + args, list(expect)))
    combo("min depth above max depth", ["--min-depth", "3", "--max-depth", "2"], "--min-depth", "--max-depth")
    combo("min depth equal to max depth", ["--min-depth", "2", "--max-depth", "2"], "--min-depth", "--max-depth")
    combo("mu below the voxel size", ["--voxel-size", "0.05", "--mu", "0.01"], "mu > voxel size")
    combo("dense volume offset overflowing an int", ["--index", "dense", "--volume-offset", "2147483600", "0", "0"], "--volume-offset")
    combo("dense volume larger than memory", ["--index", "dense", "--volume-size", "65536", "65536", "4096"], "GiB", "--volume-size")
    combo("dense volume of 2048^3 f voxels", ["--index", "dense", "--voxel", "f", "--volume-size", "2048", "2048", "2048"], "GiB")
    combo("hash table larger than memory", ["--hash-buckets", "1073741824", "--hash-excess", "1073741823"], "--hash-buckets")
    combo("dense volume settings with the hash index", ["--volume-size", "64", "64", "64"], "--volume-size", "--index dense")
    combo("hash settings with the dense index", ["--index", "dense", "--hash-buckets", "1024"], "--hash-buckets")
    combo("tracker settings with ground-truth poses", ["--poses", "groundtruth", "--tracker", "icp"], "--tracker", "groundtruth")
    combo("tracker iterations with ground-truth poses", ["--poses", "groundtruth", "--tracker-iterations", "5"], "--tracker-iterations")
    combo("three iteration counts for two levels", ["--tracker-levels", "bb", "--tracker-iterations", "5", "5", "5"], "iterations",
          "expected 1 or 2 values")
    combo("--device-uri without --live", ["--device-uri", "xyz"], "--device-uri", "--live")
    combo("swap blocks per frame without swapping", ["--swap-blocks-per-frame", "10"], "--swap-blocks-per-frame", "swapping")
    combo("iPhone confidence on a TUM folder", ["--min-confidence", "2"], "--min-confidence", "not a Stray Scanner capture")
    combo("classes asked of a voxel type without them", ["--voxel", "s_rgb", "--mesh-per-class"], "--mesh-per-class")
    combo("classes excluded from a voxel type without them", ["--voxel", "s_rgb", "--exclude-classes", "3"], "--exclude-classes")
    combo("labels with a voxel type without classes", ["--voxel", "s", "--labels", "{tum}/labels.txt"], "--labels")
    combo("swapping with the dense index", ["--swap", "--index", "dense"], "hash index")
    combo("the GPU on a machine without one", ["--device", "cuda"], "CUDA")
    # A map that fills up runs on, and says so when it happens (not only in the summary at the end).
    c.append(Case("combination", "a map too small for the scene", base + ["--max-blocks", "50"],
                  ["warning: frame", "the map is full (50 voxel blocks", "--swap"], ok_exit=True))
    c.append(Case("combination", "--frames 0 without a map", [TUM, "--frames", "0", "--out", OUT], ["--frames 0", "--load-map"]))
    c.append(Case("combination", "a map with another voxel type asked for", ["--load-map", "{map}", "--voxel", "f", "--frames", "0",
                                                                               "--out", OUT], ["--voxel", "'s' voxels"]))
    c.append(Case("combination", "a map with another voxel size asked for", [TUM, "--load-map", "{map}", "--voxel-size", "0.01",
                                                                              "--frames", "1", "--out", OUT], ["--voxel-size"]))
    c.append(Case("combination", "--live with a SOURCE", [TUM, "--live", "--out", OUT], ["--live"]))
    c.append(Case("combination", "a synthetic source with --depth files", ["synthetic:2", "--depth", "x/%04i.pgm", "--out", OUT],
                  ["--rgb/--depth"]))

    # ---- PPM/PGM patterns and the calibration they need
    def seq(what, args, expect, setup=None, ok_exit=False, check=None, calib="{ppm}/calib.txt", category="ppm/pgm"):
        c.append(Case(category, what, ["--rgb", "{ppm}/%04i.ppm", "--depth", "{ppm}/%04i.pgm", "--calib", calib,
                                       "--render-every", "0", "--out", OUT] + args, expect, ok_exit, setup, check))
    c.append(Case("ppm/pgm", "an rgb pattern without a depth pattern", ["--rgb", "{ppm}/%04i.ppm", "--calib", "{ppm}/calib.txt",
                                                                         "--out", OUT], ["depth file pattern", "--depth"]))
    c.append(Case("ppm/pgm", "a depth pattern without a calibration", ["--depth", "{ppm}/%04i.pgm", "--out", OUT], ["calibration"]))
    c.append(Case("ppm/pgm", "a pattern with %s", ["--depth", "{ppm}/%s.pgm", "--calib", "{ppm}/calib.txt", "--out", OUT],
                  ["%s", "unsupported conversion"]))
    c.append(Case("ppm/pgm", "a pattern with two conversions", ["--depth", "{ppm}/%d%d.pgm", "--calib", "{ppm}/calib.txt", "--out", OUT],
                  ["more than one conversion"]))
    c.append(Case("ppm/pgm", "a pattern with no conversion", ["--depth", "{ppm}/0000.pgm", "--calib", "{ppm}/calib.txt", "--out", OUT],
                  ["no integer conversion"]))
    c.append(Case("ppm/pgm", "no first frame", ["--depth", "{ppm}/%04i.nothere", "--calib", "{ppm}/calib.txt", "--out", OUT],
                  ["0000.nothere", "does not exist"]))

    def bad_frame(what, name, data, *expect):
        seq(what, [], [name] + list(expect), setup=lambda d, n=name, b=data: write(os.path.join(d, "ppm", n), b), ok_exit=False)
    # A bad middle frame is skipped and said; the run goes on (exit 0 with the frame named on stderr).
    def skipped_frame(what, name, data, *expect):
        def check(result, case_dir):
            s = json.load(open(os.path.join(case_dir, "out", "summary.json")))
            return s["frames_unreadable"] == 1
        seq(what, [], [name, "frame 1"] + list(expect), setup=lambda d, n=name, b=data: write(os.path.join(d, "ppm", n), b) if b is not None
            else os.remove(os.path.join(d, "ppm", n)), ok_exit=True, check=check)
    skipped_frame("a truncated 16-bit PGM", "0001.pgm", b"P5\n64 48\n65535\n" + b"\x00" * 100, "truncated")
    skipped_frame("a PGM with a wrong magic", "0001.pgm", b"P2\n64 48\n65535\n" + b"\x00" * 6144, "wrong magic")
    skipped_frame("a PGM with maxval 0", "0001.pgm", b"P5\n64 48\n0\n" + b"\x00" * 6144, "maxval 0")
    skipped_frame("an 8-bit PGM as depth", "0001.pgm", b"P5\n64 48\n255\n" + b"\x00" * 3072, "8-bit PGM")
    skipped_frame("a PPM with maxval 70000", "0001.ppm", b"P6\n64 48\n70000\n" + b"\x00" * 9216, "maxval 70000")
    skipped_frame("a depth image of the wrong size", "0001.pgm", b"P5\n32 24\n65535\n" + b"\x00" * 1536, "32x24")
    skipped_frame("a PGM claiming 10^9 x 10^9 pixels", "0001.pgm", b"P5\n999999999 999999999\n65535\n" + b"\x00" * 64, "truncated")
    skipped_frame("a PGM header with letters for the width", "0001.pgm", b"P5\nabc 48\n65535\n", "expected the width")
    skipped_frame("an empty PGM", "0001.pgm", b"", "too short")
    skipped_frame("a colour frame missing in the middle", "0001.ppm", None, "missing")
    skipped_frame("a depth frame missing in the middle", "0001.pgm", None, "missing")
    def over_maxval(result, case_dir):
        s = json.load(open(os.path.join(case_dir, "out", "summary.json")))
        return s["depth_samples_out_of_range"] == 64 * 48 and s["frames_with_samples_out_of_range"] == 1
    seq("a PGM whose samples exceed its maxval", [], ["0001.pgm", "frame 1", "exceed the maximum the file declares"],
        setup=lambda d: write(os.path.join(d, "ppm", "0001.pgm"), b"P5\n64 48\n1000\n" + b"\x07\xd0" * 3072),
        ok_exit=True, check=over_maxval)
    def color_over_maxval(result, case_dir):
        s = json.load(open(os.path.join(case_dir, "out", "summary.json")))
        return s["color_samples_out_of_range"] == 64 * 48 and s["frames_with_samples_out_of_range"] == 1
    seq("a PPM whose samples exceed its maxval", [], ["frame 1", "colour samples exceed the maximum"],
        setup=lambda d: write(os.path.join(d, "ppm", "0001.ppm"), b"P6\n64 48\n100\n" + b"\xc8\x32\x32" * 3072),
        ok_exit=True, check=color_over_maxval)
    seq("a folder where a depth frame should be", [], ["0001.pgm", "frame 1"], ok_exit=True,
        setup=lambda d: (os.remove(os.path.join(d, "ppm", "0001.pgm")), os.makedirs(os.path.join(d, "ppm", "0001.pgm"))))

    # ---- calib.txt: every line, every kind of wrong value
    def calib(what, text, *expect):
        seq(what, [], ["calib.txt"] + list(expect), setup=lambda d, t=text: write(os.path.join(d, "calib.txt"), t), calib="{case}/calib.txt",
            category="calib")
    calib("an empty calibration", "", "unexpected end of file")
    calib("only the colour camera", "64 48\n50 50\n31.5 23.5\n", ":3:", "depth camera image size")
    calib("a width that is not a number", calib_with(1, "64x 48"), ":1:", "not an integer")
    calib("a zero height", calib_with(1, "64 0"), ":1:", "must be positive")
    calib("an absurd width", calib_with(5, "100000000 48"), ":5:", "larger than")
    calib("a NaN focal length", calib_with(2, "nan 50"), ":2:", "non-finite")
    calib("a focal length finite as a double, infinite as a float", calib_with(2, "1e39 50"), ":2:", "non-finite")
    calib("a focal length that is zero as a float", calib_with(6, "1e-50 50"), ":6:", "must be positive")
    calib("a negative focal length", calib_with(6, "-50 50"), ":6:", "must be positive")
    calib("a principal point outside the image", calib_with(3, "640 23.5"), ":3:", "lies outside")
    calib("a NaN principal point", calib_with(7, "31.5 nan"), ":7:", "non-finite")
    calib("three numbers for the focal lengths", calib_with(2, "50 50 50"), ":2:", "expected 2 numbers")
    calib("extrinsics that are not a rotation", calib_with(9, "2 0 0 0"), ":9:", "not a rotation")
    calib("extrinsics that are a reflection", calib_with(11, "0 0 -1 0"), ":9:", "reflection")
    calib("an extrinsic translation of 1e39", calib_with(9, "1 0 0 1e39"), ":9:", "non-finite")
    calib("a short extrinsics row", calib_with(10, "0 1 0"), ":10:", "expected 4 numbers")
    calib("an unknown disparity keyword", calib_with(13, "linear 0.0002 0"), ":13:", "unknown disparity calibration type")
    calib("a zero depth scale", calib_with(13, "affine 0 0"), ":13:", "depth scale must be positive")
    calib("a depth scale that is zero as a float", calib_with(13, "affine 1e-50 0"), ":13:", "depth scale must be positive")
    calib("a depth offset infinite as a float", calib_with(13, "affine 0.0002 1e39"), ":13:", "non-finite")
    calib("a negative Kinect k2", calib_with(13, "kinect 1135 -0.08"), ":13:", "k2 must be positive")
    calib("a depth scale in metres given for millimetres", calib_with(13, "affine 1 0"), ":13:", "coarser than any depth camera")
    calib("a depth scale that reaches no camera's range", calib_with(13, "affine 1e-9 0"), ":13:", "no depth camera's range")
    calib("a depth offset of metres", calib_with(13, "affine 0.0002 5"), ":13:", "depth offset 5 m")
    calib("a Kinect baseline in millimetres", calib_with(13, "kinect 1135 81.9"), ":13:", "Kinect baseline")
    calib("a Kinect offset that puts every sample behind the camera", calib_with(13, "kinect -5 0.08"), ":13:",
          "no sample a positive depth")
    calib("lens distortion that folds the image", GOOD_CALIB + "distortion_rgb -5 0 0 0 0\n", ":14:", "folds the image")
    calib("a tangential distortion of no lens", GOOD_CALIB + "distortion_depth 0 0 3 0 0\n", ":14:", "moves an image corner")
    # Legal but unusual: accepted with a warning; here every depth then falls short of the view frustum, so
    # the run fuses nothing and says so with exit status 4 (its outputs written).
    seq("a depth scale whose depths all fall short of the frustum", [], ["warning", "calib.txt", "was fused",
        "depth scale"], setup=lambda d: write(os.path.join(d, "calib.txt"), calib_with(13, "affine 0.000001 0")),
        calib="{case}/calib.txt", category="calib",
        check=None)
    calib("NaN lens distortion", GOOD_CALIB + "distortion_rgb 0.1 nan 0 0 0\n", ":14:", "non-finite")
    calib("lens distortion infinite as a float", GOOD_CALIB + "distortion_depth 1e39 0 0 0 0\n", ":14:", "non-finite")
    calib("lens distortion given twice", GOOD_CALIB + "distortion_rgb 0 0 0 0 0\ndistortion_rgb 0 0 0 0 0\n", ":15:", "given twice")
    calib("four distortion numbers", GOOD_CALIB + "distortion_rgb 0.1 0 0 0\n", ":14:", "expected 5 numbers")
    calib("garbage after the disparity line", GOOD_CALIB + "hello\n", ":14:", "unexpected content")
    calib("binary garbage", bytes(range(256)) * 4, "calib.txt")
    calib("one 100 kB line", "5" * 100000, ":1:", "line longer than")
    calib("terminal escape codes in a value", calib_with(2, "\x1b[31m50 50"), ":2:", "\\x1b")
    c.append(Case("calib", "a folder given as the calibration", ["--rgb", "{ppm}/%04i.ppm", "--depth", "{ppm}/%04i.pgm", "--calib",
                                                                  "{ppm}", "--out", OUT], ["is a folder, not a file"]))
    c.append(Case("calib", "a missing calibration", ["--rgb", "{ppm}/%04i.ppm", "--depth", "{ppm}/%04i.pgm", "--calib", "{ppm}/none.txt",
                                                     "--out", OUT], ["none.txt", "no such file"]))
    c.append(Case("calib", "/dev/zero as the calibration", ["--rgb", "{ppm}/%04i.ppm", "--depth", "{ppm}/%04i.pgm", "--calib",
                                                            "/dev/zero", "--out", OUT], ["/dev/zero", "line longer than"]))

    # ---- TUM folders: lists, ground truth, images
    def tum(what, edit, expect, ok_exit=False, check=None, args=()):
        def setup(d, edit=edit):
            edit(FIX.copy_tum(d))
        c.append(Case("tum", what, ["{case}/tum", "--frames", "3", "--render-every", "0", "--out", OUT] + list(args), expect, ok_exit,
                      setup, check))

    def first_listed(t, list_name):
        for line in open(os.path.join(t, list_name)):
            if line.strip() and not line.startswith("#"):
                return line.split()
    def second_listed(t, list_name):
        rows = [l.split() for l in open(os.path.join(t, list_name)) if l.strip() and not l.startswith("#")]
        return rows[1]
    def gt(text):
        return lambda t: write(os.path.join(t, "groundtruth.txt"), text)
    tum("an image list line with three fields", lambda t: write(os.path.join(t, "rgb.txt"), "1.0 rgb/a.jpg extra\n"),
        ["rgb.txt:1", "expected 'timestamp filename'"])
    tum("a NaN timestamp in the list", lambda t: write(os.path.join(t, "depth.txt"), "nan depth/x.png\n"), ["depth.txt:1", "not a timestamp"])
    tum("binary garbage as the image list", lambda t: write(os.path.join(t, "rgb.txt"), bytes(range(1, 256)) * 8), ["rgb.txt"])
    tum("an image list that is a folder", lambda t: (os.remove(os.path.join(t, "rgb.txt")), os.makedirs(os.path.join(t, "rgb.txt"))),
        ["rgb.txt"])
    tum("no listed image on disk", lambda t: shutil.rmtree(os.path.join(t, "depth")), ["no frame"])
    tum("ground truth with seven numbers", gt("1000.0 0 0 0 0 0 1\n"), ["groundtruth.txt:1", "expected 8 numbers"])
    tum("ground truth with NaN", gt("1000.0 nan 0 0 0 0 0 1\n"), ["groundtruth.txt:1", "non-finite"])
    tum("ground truth infinite as a float", gt("1000.0 1e39 0 0 0 0 0 1\n"), ["groundtruth.txt:1", "non-finite"])
    tum("ground truth with a zero quaternion", gt("1000.0 0 0 0 0 0 0 0\n"), ["groundtruth.txt:1", "zero-length quaternion"])
    tum("ground truth with one time and two poses", gt("1000.0 0 0 0 0 0 0 1\n1000.0 1 0 0 0 0 0 1\n"), ["groundtruth.txt:2", "given twice"])
    tum("ground truth going back in time", gt("1000.1 0 0 0 0 0 0 1\n1000.0 0 0 0 0 0 0 1\n"), ["groundtruth.txt:2", "must not decrease"])
    tum("ground truth that is a folder", lambda t: (os.remove(os.path.join(t, "groundtruth.txt")), os.makedirs(os.path.join(t, "groundtruth.txt"))),
        ["groundtruth.txt", "folder"])

    def image(list_name, replace, which=second_listed):
        def edit(t):
            name = which(t, list_name)[1]
            path = os.path.join(t, name)
            data = replace(read(path)) if callable(replace) else replace
            if data is None:
                os.remove(path)
                os.makedirs(path)
            else:
                write(path, data)
        return edit
    def frame_skipped(result, case_dir):
        s = json.load(open(os.path.join(case_dir, "out", "summary.json")))
        return s["frames_unreadable"] == 1
    tum("a truncated colour JPEG", image("rgb.txt", lambda b: b[: len(b) // 2]), ["frame 1", "corrupt JPEG"], True, frame_skipped)
    tum("a colour JPEG with garbage in the middle", image("rgb.txt", lambda b: b[: len(b) // 2] + b"\xff" * 32 + b[len(b) // 2 + 32:]),
        ["frame 1", "corrupt JPEG"], True, frame_skipped)
    tum("a colour JPEG of only its header", image("rgb.txt", lambda b: b[:4]), ["frame 1", "corrupt JPEG"], True, frame_skipped)
    tum("an 8-bit depth PNG", image("depth.txt", png(64, 48, 8, 0, [b"\x10" * 64] * 48)), ["frame 1", "16-bit single-channel"], True,
        frame_skipped)
    tum("a depth PNG of the wrong size", image("depth.txt", depth_png(32, 24)), ["frame 1", "32x24"], True, frame_skipped)
    tum("a truncated depth PNG", image("depth.txt", lambda b: b[: len(b) // 2]), ["frame 1", "cannot decode"], True, frame_skipped)
    tum("a PNG claiming 2^31 x 2^31 pixels", image("depth.txt", lambda b: b[:16] + b"\x7f\xff\xff\xff\x7f\xff\xff\xff" + b[24:]),
        ["frame 1", "too large"], True, frame_skipped)
    tum("a folder where a colour image should be", image("rgb.txt", None), ["frame 1", "folder"], True, frame_skipped)
    def first_frame_not_good(result, case_dir):
        frames = json.load(open(os.path.join(case_dir, "out", "timings.json")))["frames"]
        return frames[0]["tracking"] != "good" and not frames[0]["fused"]
    tum("a first depth image of zeros only (nothing to track)", image("depth.txt", depth_png(64, 48, 0), first_listed), [], True,
        check=first_frame_not_good)

    # ---- environment variables: garbage is said and ignored, the run goes on with the default
    for name, value, reason in (("VOXFUSE_NUM_THREADS", "abc", "not a thread count"), ("VOXFUSE_NUM_THREADS", "-3", "not a thread count"),
                                ("VOXFUSE_NUM_THREADS", "99999999999", "not a thread count"), ("OMP_NUM_THREADS", "x", "not a thread count"),
                                ("VOXFUSE_SPIN_US", "nan", "not a number of microseconds"), ("VOXFUSE_SPIN_US", "1e99", "not a number of microseconds")):
        c.append(Case("environment", "%s=%s" % (name, value), ["synthetic:3", "--render-every", "0", "--out", OUT],
                      ["ignoring " + name, reason], True, env={name: value}))

    # ---- per-frame folders: pose files and intrinsics
    def frames(what, edit, expect, ok_exit=False, check=None):
        def setup(d, edit=edit):
            edit(FIX.frame_folder(d))
        c.append(Case("frame folder", what, ["{case}/frames", "--render-every", "0", "--out", OUT], expect, ok_exit, setup, check))
    pose1 = lambda text: lambda f: write(os.path.join(f, "frame-000001.pose.txt"), text)
    frames("a pose with one NaN", pose1("1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"), ["frame-000001.pose.txt", "non-finite"])
    frames("a pose infinite as a float", pose1("1 0 0 1e39\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"), ["frame-000001.pose.txt", "non-finite"])
    frames("a pose that is not a rotation", pose1("2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"), ["frame-000001.pose.txt", "not a rotation"])
    frames("a pose that is a reflection", pose1("-1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"), ["frame-000001.pose.txt", "reflection"])
    frames("a pose with three rows", pose1("1 0 0 0\n0 1 0 0\n0 0 1 0\n"), ["frame-000001.pose.txt", "unexpected end of file"])
    frames("a pose whose last row is not 0 0 0 1", pose1("1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n"), ["frame-000001.pose.txt", "0 0 0 1"])
    frames("a pose marking lost tracking (-inf)", pose1("-inf -inf -inf -inf\n" * 3 + "0 0 0 1\n"), ["mark lost tracking"], True)
    kfile = lambda text: lambda f: write(os.path.join(f, "intrinsics.K.txt"), text)
    frames("a NaN in K", kfile("nan 0 31.5\n0 50 23.5\n0 0 1\n"), ["intrinsics.K.txt", "non-finite"])
    frames("a K with skew", kfile("50 1 31.5\n0 50 23.5\n0 0 1\n"), ["intrinsics.K.txt", "no skew"])
    frames("a negative focal length in K", kfile("-50 0 31.5\n0 50 23.5\n0 0 1\n"), ["intrinsics.K.txt", "must be positive"])
    frames("a principal point outside the images", kfile("50 0 320\n0 50 23.5\n0 0 1\n"), ["intrinsics.K.txt", "lies outside"])
    frames("no intrinsics", lambda f: os.remove(os.path.join(f, "intrinsics.K.txt")), ["intrinsics.K.txt"])
    frames("a damaged colour JPEG", lambda f: write(os.path.join(f, "frame-000001.color.jpg"), read(os.path.join(f, "frame-000001.color.jpg"))[:300]),
           ["frame-000001.color.jpg", "frame 1", "corrupt JPEG"], True)

    # ---- semantic labels
    def labels(what, args, expect, setup=None, ok_exit=False):
        c.append(Case("labels", what, ["{case}/tum", "--frames", "3", "--render-every", "0", "--out", OUT, "--voxel", "s_rgb_label"] + args,
                      expect, ok_exit, lambda d, s=setup: (FIX.copy_tum(d), s(os.path.join(d, "tum")) if s else None)))
    labels("an empty label folder", ["--labels", "{case}/empty"], ["empty", "no label images"], lambda t: os.makedirs(os.path.join(t, "..", "empty")))
    labels("a label folder of JPEGs", ["--labels", "{case}/jpgs"], ["JPEG"], lambda t: shutil.copytree(os.path.join(t, "rgb"), os.path.join(t, "..", "jpgs")))
    labels("a label image file given as --labels", ["--labels", "{case}/tum/labels/" + "x.png"], ["labels"],
           lambda t: write(os.path.join(t, "labels", "x.png"), png(2, 2, 8, 0, [b"\x01\x02"] * 2)))
    labels("a missing label folder", ["--labels", "{case}/none"], ["none", "no such label folder"])
    labels("a label list with a bad line", ["--labels", "{case}/tum/labels.txt"], ["labels.txt:1"],
           lambda t: write(os.path.join(t, "labels.txt"), "x y z\n"))
    labels("a colour label image", [], ["frame 1", "channels"], lambda t: write(os.path.join(t, "labels", sorted(os.listdir(os.path.join(t, "labels")))[1]),
                                                                              png(64, 48, 8, 2, [b"\x01\x02\x03" * 64] * 48)), True)
    labels("a truncated label PNG", [], ["frame 1"], lambda t: write(os.path.join(t, "labels", sorted(os.listdir(os.path.join(t, "labels")))[1]),
                                                                    png(64, 48, 8, 0, [b"\x01" * 64] * 48)[:60]), True)
    labels("a 1-bit label PNG: classes 0 and 1, fused", [], ["outputs"],
           lambda t: write(os.path.join(t, "labels", sorted(os.listdir(os.path.join(t, "labels")))[1]), png(64, 48, 1, 0, [b"\xff" * 8] * 48)),
           True)
    labels("a label image of another aspect ratio", [], ["frame 1"], lambda t: write(os.path.join(t, "labels", sorted(os.listdir(os.path.join(t, "labels")))[1]),
                                                                                    png(64, 64, 8, 0, [b"\x01" * 64] * 64)), True)

    # ---- tracker settings files
    def tracker(what, text, *expect):
        c.append(Case("tracker config", what, base + ["--tracker-config", "{case}/tracker.txt"], ["tracker.txt"] + list(expect),
                      setup=lambda d, t=text: write(os.path.join(d, "tracker.txt"), t)))
    tracker("an unknown key", "speed = 3\n", ":1:", "unknown tracker setting")
    tracker("a value that is not a number", "max_motion_m = far\n", ":1:", "not a number")
    tracker("a NaN value", "robust_scale_m = nan\n", ":1:", "not a number")
    tracker("unknown level types", "levels = xyz\n", ":1:", "level types")
    tracker("iterations for another number of levels", "levels = bb\niterations = 1 2 3\n", ":2:", "expected 1 or 2 values")
    tracker("failed above good", "good_inlier_ratio = 0.2\nfailed_inlier_ratio = 0.5\n", ":2:", "must not exceed")
    tracker("a line without '='", "tracker icp\n", ":1:", "key = value")
    tracker("a 2 MB file", "# " + "x" * 2000000 + "\n", "larger than")
    tracker("a value infinite as a float", "robust_scale_m = 1e39\n", ":1:", "float range")
    tracker("zero iterations", "iterations = 0\n", ":1:", "1..1000")
    tracker("a negative motion bound", "max_motion_m = -1\n", ":1:", "must be > 0")
    tracker("an inlier ratio above 1", "good_inlier_ratio = 2\n", ":1:", "[0, 1]")
    tracker("17 far-field keyframes", "far_field_keyframes = 17\n", ":1:", "0..16")
    tracker("a far-field point share of 0", "far_field_point_share = 0\n", ":1:", "(0, 1]")
    tracker("a negative far-field spacing", "far_field_spacing_m = -1\n", ":1:", ">= 0")
    tracker("an infinite far-field angle", "far_field_spacing_deg = inf\n", ":1:", "not a number")
    c.append(Case("tracker config", "a folder as the settings file", base + ["--tracker-config", "{case}"], ["--tracker-config"]))
    c.append(Case("tracker config", "/dev/zero as the settings file", base + ["--tracker-config", "/dev/zero"], ["/dev/zero", "larger than"]))

    # ---- map files
    def mapfile(what, make, *expect):
        c.append(Case("map file", what, ["--load-map", "{case}/bad.vfm", "--frames", "0", "--out", OUT], ["bad.vfm"] + list(expect),
                      setup=lambda d, m=make: write(os.path.join(d, "bad.vfm"), m(read(FIX.map)))))
    def patched(offset, value_bytes, fix_crc=True):
        def make(b):
            b = bytearray(b)
            b[offset:offset + len(value_bytes)] = value_bytes
            if fix_crc:
                b[271:275] = struct.pack("<I", zlib.crc32(bytes(b[16:271])) & 0xFFFFFFFF)  # the header's 255 bytes, then its CRC
            return bytes(b)
        return make
    mapfile("a text file", lambda b: b"hello, map\n", "not a VoxFuse map")
    mapfile("an empty file", lambda b: b"", "truncated")
    mapfile("half a map", lambda b: b[: len(b) // 2], "truncated")
    mapfile("a flipped byte in the voxels", lambda b: b[:-100] + bytes([b[-100] ^ 1]) + b[-99:], "checksum")
    mapfile("a flipped byte in the header", lambda b: b[:40] + bytes([b[40] ^ 1]) + b[41:], "checksum")
    mapfile("version 99", patched(8, struct.pack("<I", 99), False), "version 99")
    mapfile("a negative bucket count, checksum fixed", patched(16 + 24, struct.pack("<i", -5)), "hash settings are out of range")
    mapfile("a voxel size of NaN, checksum fixed", patched(16 + 68, struct.pack("<f", float("nan"))), "out of range")
    mapfile("bytes after the end marker", lambda b: b + b"extra", "after the end marker")
    c.append(Case("map file", "a folder as the map", ["--load-map", "{case}", "--frames", "0", "--out", OUT], ["--load-map"]))
    # A good map (5 mm 's' voxels, hash) with the options that would change what it is (the voxel type
    # and size: under "combination").
    for args, expect in [(["--voxel", "s_label", "--labels", "{tum}/labels.txt"], ["room.vfm", "--voxel"]),
                         (["--labels", "{tum}/labels.txt"], ["--labels needs a voxel type with classes"]),
                         (["--index", "dense"], ["room.vfm", "--index cannot change it"]), (["--mu", "0.5"], ["room.vfm", "--mu cannot change it"]),
                         (["--hash-buckets", "1024"], ["room.vfm", "--hash-buckets cannot change it"]),
                         (["--max-blocks", "1"], ["room.vfm", "more than the voxel array's maximum"]), (["--device", "cuda"], ["CUDA"])]:
        c.append(Case("map file", "a map loaded with " + " ".join(args),
                      [TUM, "--load-map", "{map}", "--frames", "1", "--render-every", "0", "--out", OUT] + args, expect))
    # Read whole before the new one replaces it: the map grows, and no temporary file is left.
    c.append(Case("map file", "a map saved over the map it loads", [TUM, "--load-map", "{case}/m.vfm", "--save-map", "{case}/m.vfm", "--skip", "2",
                                                                    "--frames", "1", "--poses", "groundtruth", "--render-every", "0", "--out", OUT],
                  ["m.vfm"], ok_exit=True, setup=lambda d: shutil.copy(FIX.map, os.path.join(d, "m.vfm")),
                  check=lambda r, d: os.path.getsize(os.path.join(d, "m.vfm")) > os.path.getsize(FIX.map) and not [
                      n for n in os.listdir(d) if n.startswith("m.vfm") and n != "m.vfm"]))

    # ---- swapping budgets at their limits: the run goes on, says what did not fit
    c.append(Case("swapping", "one active block", ["{tum}", "--active-blocks", "1", "--frames", "2", "--render-every", "0", "--out", OUT],
                  ["the map is full", "--active-blocks"], ok_exit=True))
    c.append(Case("swapping", "--active-blocks 0: as many as --max-blocks", ["{tum}", "--active-blocks", "0", "--frames", "2",
                                                                          "--render-every", "0", "--out", OUT],
                  ["swapping", "blocks stored in memory"], ok_exit=True))
    c.append(Case("swapping", "one block moved per frame", ["{tum}", "--active-blocks", "3000", "--swap-blocks-per-frame", "1", "--frames", "3",
                                                             "--render-every", "0", "--out", OUT], ["--active-blocks"], ok_exit=True))

    # ---- output paths
    def output(what, args, expect, ok_exit=False, setup=None, check=None, needs_mount=False, tum_source=TUM):
        c.append(Case("output", what, [tum_source, "--frames", "2", "--render-every", "0"] + args, expect, ok_exit, setup, check,
                      needs_mount=needs_mount))
    output("--out is a file", ["--out", "{case}/file"], ["--out", "is a file"], setup=lambda d: write(os.path.join(d, "file"), "x"))
    output("--out below a file", ["--out", "{case}/file/sub"], ["file"], setup=lambda d: write(os.path.join(d, "file"), "x"))
    output("--out holding an earlier run", ["--out", "{case}/out"], ["--out", "earlier run", "--overwrite"],
           setup=lambda d: write(os.path.join(d, "out", "summary.json"), "{}"))
    output("--out holding an earlier run, with --overwrite", ["--out", "{case}/out", "--overwrite"], ["--overwrite: removed 2 files"], True,
           setup=lambda d: (write(os.path.join(d, "out", "summary.json"), "{}"), write(os.path.join(d, "out", "render_000050.png"), "x")),
           check=lambda r, d: not os.path.exists(os.path.join(d, "out", "render_000050.png")))
    output("a file of an interrupted write left in --out", ["--out", "{case}/out"], ["earlier run"],
           setup=lambda d: write(os.path.join(d, "out", ".mesh.partial-99.ply"), "x"))
    output("--mesh-file into a folder", ["--out", "{case}/out", "--mesh-file", "{case}"], ["is a folder"])
    output("--mesh-file in a missing folder", ["--out", "{case}/out", "--mesh-file", "{case}/none/m.ply"], ["no such folder"])
    output("--mesh-file with an unknown format", ["--out", "{case}/out", "--mesh-file", "{case}/m.xyz"], ["m.xyz", "unknown mesh format"])
    output("--save-map into a folder", ["--out", "{case}/out", "--save-map", "{case}"], ["is a folder"])
    output("--save-map in a missing folder", ["--out", "{case}/out", "--save-map", "{case}/none/m.vfm"], ["no such folder"])
    output("--swap-file in a missing folder", ["--out", "{case}/out", "--swap", "--swap-file", "{case}/none/swap"], ["swap"])
    output("--swap-file that is a folder", ["--out", "{case}/out", "--swap", "--swap-file", "{case}"], ["swap"])

    def json_valid(name):
        def check(result, case_dir):
            for root, _, files in os.walk(case_dir):
                if name in files:
                    data = read(os.path.join(root, name))
                    json.loads(data.decode("utf-8"))  # strict: must be UTF-8 JSON
                    return True
            return False
        return check
    output("a Unicode output folder", ["--out", "{case}/données/出力"], [], True, check=json_valid("summary.json"))
    output("an output folder that is not UTF-8", ["--out", b"{case}/bad\xff\xfename".decode("utf-8", "surrogateescape")], [], True,
           check=json_valid("summary.json"))
    output("a source folder that is not UTF-8", ["--out", "{case}/out"], [], True, check=json_valid("summary.json"),
           setup=lambda d: shutil.copytree(FIX.tum, os.path.join(d, b"src\xff\xfe".decode("utf-8", "surrogateescape"))),
           tum_source=b"{case}/src\xff\xfe".decode("utf-8", "surrogateescape"))
    output("a full disk", ["--out", "{mnt}/out", "--mesh"], ["disk full"], needs_mount="size=300k")
    output("a read-only folder", ["--out", "{mnt}"], ["read-only file system"], needs_mount="ro")

    # ---- signals
    def interrupted(status):
        def check(result, case_dir):
            out = os.path.join(case_dir, "out")
            s = json.load(open(os.path.join(out, "summary.json")))
            poses = [l for l in open(os.path.join(out, "trajectory.txt")) if l[:1].isdigit()]
            return s["interrupted"] and result.returncode == status and len(poses) == s["frames"] > 0 and os.path.exists(
                os.path.join(out, "mesh.ply"))
        return check
    # Signals go once the first frame is done (its render is written), so that there is work to keep.
    first_render = "{out}/render_000000.png"
    c.append(Case("signal", "Ctrl-C during a run", [ROOM, "--out", OUT, "--mesh", "--render-every", "1000"], ["interrupted"], True,
                  check=interrupted(130), interrupt=[(first_render, signal.SIGINT)]))
    c.append(Case("signal", "SIGTERM during a run", [ROOM, "--out", OUT, "--mesh", "--render-every", "1000"], ["interrupted"], True,
                  check=interrupted(143), interrupt=[(first_render, signal.SIGTERM)]))
    # The second Ctrl-C must come before the first one's outputs are written. Without a mesh, a first
    # Ctrl-C that meets the loop between frames ends the run in about 17 ms, which a busy machine's
    # scheduling of this script outran now and then; the mesh and the cloud keep the run writing for
    # 270 ms and more after it. 20 ms apart: the kernel delivers a signal within microseconds, so the
    # two are never merged into one.
    c.append(Case("signal", "Ctrl-C twice", [ROOM, "--out", OUT, "--render-every", "1000", "--mesh", "--cloud"], ["quitting now"], True,
                  check=lambda r, d: r.returncode == 130 and not os.path.exists(os.path.join(d, "out", "summary.json")),
                  interrupt=[(first_render, signal.SIGINT), (0.02, signal.SIGINT)]))
    # 2000 synthetic frames take minutes: the signal comes mid-run however fast the build is.
    c.append(Case("signal", "Ctrl-C during the benchmark", ["synthetic:2000", "--warmup", "0", "--json", "{case}/bench.json"], ["interrupted"],
                  True, check=lambda r, d: r.returncode == 130 and json.load(open(os.path.join(d, "bench.json")))["interrupted"],
                  program="bench", interrupt=[(5.0, signal.SIGINT)]))

    # ---- recordings
    c.append(Case("oni", "random bytes named .oni", ["{case}/x.oni", "--out", OUT], ["x.oni"],
                  setup=lambda d: write(os.path.join(d, "x.oni"), os.urandom(4096))))
    c.append(Case("oni", "a truncated .oni recording", ["{case}/t.oni", "--out", OUT, "--render-every", "0"], ["t.oni"],
                  setup=lambda d: write(os.path.join(d, "t.oni"), read(ONI)[: len(read(ONI)) // 3]) if os.path.exists(ONI) else None))
    c.append(Case("source", "a source that does not exist", ["{case}/none", "--out", OUT], ["none", "no such file or folder"]))
    c.append(Case("source", "a folder that is no known source", ["{case}", "--out", "{case}/out"], ["not a known image source"]))
    c.append(Case("source", "synthetic:abc", ["synthetic:abc", "--out", OUT], ["synthetic:abc"]))

    # ---- the Python API: arrays and calls a script gets wrong; an uncaught error exits 1 with its message
    START = ("import sys, numpy as np, voxfuse\n"
             "source = voxfuse.open_source('{tum}')\n"
             "f = next(iter(source))\n"
             "p = voxfuse.Pipeline(source.calib, voxel_size=0.01)\n")
    def py(what, code, *expect, ok_exit=False):
        c.append(Case("python", what, ["-c", START + code], list(expect), ok_exit, program="python"))
    py("depth of dtype float16", "p.process(f.depth.astype(np.float16))", "TypeError", "float16")
    py("depth of dtype int32", "p.process(f.depth.astype(np.int32))", "TypeError", "int32")
    py("depth transposed", "p.process(np.ascontiguousarray(f.depth.T))", "ValueError", "shape (48, 64)")
    py("depth in Fortran order is read as its values",
       "q = voxfuse.Pipeline(source.calib, voxel_size=0.01)\n"
       "a, b = p.process(f.depth), q.process(np.asfortranarray(f.depth))\n"
       "print('same' if (a.pose == b.pose).all() and a.fused == b.fused else 'differ')", "same", ok_exit=True)
    py("depth in metres with NaN and infinities: no measurement there",
       "d = f.depth * np.float32(source.calib.depth_scale); d[::3] = np.nan; d[1::5] = np.inf; d[2::7] = -1\n"
       "r = p.process(d)\nprint('handled', r.quality)", "handled", ok_exit=True)
    py("rgb of dtype float32", "p.process(f.depth, f.rgb.astype(np.float32))", "TypeError", "uint8")
    py("rgb with 2 channels", "p.process(f.depth, f.rgb[..., :2])", "ValueError", "3 or 4")
    py("labels of dtype int64", "p.process(f.depth, labels=np.zeros((48, 64), np.int64))", "TypeError", "uint16")
    py("a pose of NaN", "p.process(f.depth, pose=np.full((4, 4), np.nan))", "ValueError", "not finite")
    py("a pose that scales", "p.process(f.depth, pose=np.diag([2.0, 2.0, 2.0, 1.0]))", "ConfigError", "not a rotation")
    py("a timestamp of NaN", "p.process(f.depth, timestamp=float('nan'))", "ValueError", "timestamp")
    py("an unknown setting", "voxfuse.Pipeline(source.calib, voxel_sise=0.01)", "TypeError", "voxel_sise")
    py("a setting of the wrong type", "voxfuse.Pipeline(source.calib, voxel_size='fine')", "TypeError", "voxel_size")
    py("a setting out of range", "voxfuse.Pipeline(source.calib, voxel_size=-1.0)", "ConfigError", "voxel_size")
    py("an unknown render mode", "p.process(f.depth)\np.render('sparkly')", "ConfigError", "sparkly")
    py("calls after an error go on",
       "try:\n    p.process(f.depth[:10])\nexcept ValueError:\n    pass\n"
       "r = p.process(f.depth)\nm = p.extract_mesh()\nprint('went on', p.frames_processed, r.fused, len(m.faces) > 0)",
       "went on 1 True True", ok_exit=True)
    py("from_map on half a map file",
       "open('half.vfm', 'wb').write(open('{map}', 'rb').read()[:100000])\nvoxfuse.Pipeline.from_map('half.vfm')", "half.vfm", "truncated")
    py("from_map on a missing file", "voxfuse.Pipeline.from_map('none.vfm')", "none.vfm")
    py("from_map with a setting the map decides", "voxfuse.Pipeline.from_map('{map}', voxel_size=0.01)", "ConfigError", "voxel_size")
    py("a frame made from arrays of another size", "voxfuse.Frame(f.depth[:, :10], calib=source.calib)", "ValueError", "shape")
    py("RealSense input without pyrealsense2", "sys.modules['pyrealsense2'] = None\nvoxfuse.open_source('walk.bag')",
       "ImportError", "pip install pyrealsense2")
    py("Rerun logging without rerun-sdk", "sys.modules['rerun'] = None\np.log_to_rerun(p.process(f.depth), f)", "ImportError",
       "pip install rerun-sdk")
    py("python -m voxfuse with a setting that does not exist", "import voxfuse.__main__ as m\n"
       "sys.exit(m.main(['{tum}', '--out', 'o', '--set', 'voxel_sise=1']))", "unknown setting")
    py("python -m voxfuse with a RealSense recording that is no recording",
       "open('junk.bag', 'wb').write(b'junk' * 1000)\nimport voxfuse.__main__ as m\nsys.exit(m.main(['junk.bag', '--out', 'o']))",
       "junk.bag")

    # ---- voxfuse_bench: every option
    def bench(what, args, *expect):
        json_arg = [] if "--json" in args else ["--json", "{case}/b.json"]
        c.append(Case("bench", what, ["synthetic:5"] + json_arg + args, list(expect), program="bench"))
    for option, values in {"--frames": ["-1", "x"], "--warmup": ["-1"], "--voxel-size": ["nan", "0", "1e39", "-1", "1e-50"],
                           "--mu": ["nan", "-1"], "--repeats": ["0", "1000"], "--cloud-voxel": ["1e-12", "nan"],
                           "--occupancy": ["1e-9", "nan", "inf"], "--active-blocks": ["-1"], "--label-ignore": ["-5"]}.items():
        for v in values:
            bench(f"{option} {v}", [option, v], option, v)
    bench("--occupancy-pixel-step 0", ["--occupancy", "0.05", "--occupancy-pixel-step", "0"], "--occupancy-pixel-step")
    bench("--occupancy-pixel-step without --occupancy", ["--occupancy-pixel-step", "2"], "--occupancy-pixel-step", "--occupancy")
    bench("--swap-blocks-per-frame without swapping", ["--swap-blocks-per-frame", "5"], "--swap-blocks-per-frame")
    bench("more warm-up frames than frames", ["--warmup", "5", "--frames", "4"], "--warmup")
    bench("--json into a folder", ["--json", "{case}"], "is a folder")
    bench("--json in a missing folder", ["--json", "{case}/none/b.json"], "no such folder")
    bench("--index sparse", ["--index", "sparse"], "--index")
    bench("--device cuda without a GPU", ["--device", "cuda"], "CUDA")
    for src in ["synthetic:0", "synthetic:abc", "synthetic:99999999999", "synthetic:2000000000", "synthetic:-1"]:
        c.append(Case("bench", "source " + src, [src, "--json", "{case}/b.json"], [src], program="bench"))
    c.append(Case("bench", "a source that does not exist", ["{case}/none", "--json", "{case}/b.json"], ["none"], program="bench"))
    return c


# ---------------------------------------------------------------------------------------------
# Running

class Mount:
    """A small tmpfs for the full-disk and read-only cases (root only)."""

    def __init__(self, options):
        self.path = tempfile.mkdtemp(prefix="voxfuse_mnt_")
        self.ok = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", self.path], capture_output=True).returncode == 0

    def close(self):
        if self.ok:
            subprocess.run(["umount", self.path], capture_output=True)
        os.rmdir(self.path)


def limit_memory():
    """At most 8 GiB of address space per program: an input that makes one grow without bound
    (reading /dev/zero as text) must not take the machine down with it."""
    resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30))


def expand(arg, values):
    for k, v in values.items():
        arg = arg.replace("{" + k + "}", v)
    return arg


def run_case(case, programs, fixtures, work, number):
    case_dir = os.path.join(work, "case%03d" % number)
    os.makedirs(case_dir)
    mount = None
    values = {"tum": fixtures.tum, "ppm": os.path.join(case_dir, "ppm"), "case": case_dir, "out": os.path.join(case_dir, "out"),
              "map": fixtures.map}
    if case.needs_mount:
        mount = Mount(case.needs_mount)
        if not mount.ok:
            mount.close()
            return "skipped", "needs mount -t tmpfs (root)"
        values["mnt"] = mount.path
    try:
        fixtures.copy_ppm(case_dir)
        if case.setup:
            case.setup(case_dir)
        env = dict(programs.env, **case.env)
        if case.program == "python":
            if not programs.python_package:
                return "skipped", "the build has no Python package"
            env["PYTHONPATH"] = programs.python_package
            program = sys.executable
        else:
            program = programs.voxfuse if case.program == "voxfuse" else programs.bench
        argv = [program] + [expand(a, values) for a in case.argv]
        start = time.time()
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=case_dir, preexec_fn=programs.limit)
        timed_out = False
        try:
            if case.interrupt:
                for when, sig in case.interrupt:  # a delay in seconds, or a file to wait for
                    if isinstance(when, str):
                        path = expand(when, values)
                        while proc.poll() is None and not os.path.exists(path) and time.time() - start < 120:
                            time.sleep(0.05)
                    else:
                        try:
                            proc.wait(timeout=when)
                        except subprocess.TimeoutExpired:
                            pass
                    if proc.poll() is not None:
                        break
                    proc.send_signal(sig)
            out, err = proc.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
            timed_out = True
        result = subprocess.CompletedProcess(argv, proc.returncode, out, err)
        text = (out + err).decode("utf-8", "replace")
        answer = next((l.strip() for l in err.decode("utf-8", "replace").splitlines()
                       if "error" in l or "interrupted" in l or "skipping" in l or "warning" in l or l.startswith("--")), "")
        if not answer:
            answer = next((l.strip() for l in reversed(text.splitlines()) if l.strip()), "")
        crashed = (proc.returncode < 0 and not case.interrupt) or proc.returncode in (134, 136, 139) or any(
            s in text for s in ("terminate called", "AddressSanitizer", "LeakSanitizer", "runtime error:", "Segmentation fault", "core dumped"))
        if timed_out:
            verdict = "hang"
        elif crashed:
            verdict = "crash"
        elif case.ok_exit or case.interrupt:
            good = all(e in text for e in case.expect)
            try:
                good = good and (case.check is None or case.check(result, case_dir))
            except Exception as e:  # a missing output, unreadable JSON...
                good = False
                answer += f" [check failed: {e.__class__.__name__}: {e}]"
            verdict = "ok" if good and (case.interrupt or proc.returncode == 0) else ("silent" if proc.returncode == 0 and not case.expect
                                                                                        else "wrong")
        elif proc.returncode == 0:
            verdict = "silent"
        else:
            verdict = "ok" if all(e in text for e in case.expect) else "unclear"
        return verdict, answer.replace("|", "/")[:160] + " (exit %d, %.1f s)" % (proc.returncode, time.time() - start)
    finally:
        if mount:
            mount.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bin", default=os.path.join(ROOT, "build"))
    parser.add_argument("--compare", help="another build whose answers are shown beside")
    parser.add_argument("--table", help="write the Markdown table here")
    parser.add_argument("--only", help="only cases whose category or description contains this")
    parser.add_argument("--quick", action="store_true", help="the signals, the output paths and every fifth other case")
    args = parser.parse_args()

    builds = [("after", Programs(args.bin))]
    if args.compare:
        builds.insert(0, ("before", Programs(args.compare)))
    work = tempfile.mkdtemp(prefix="voxfuse_bad_inputs_")
    global FIX
    FIX = Fixtures(builds[-1][1], os.path.join(work, "fixtures"))
    selected = [c for c in cases() if not args.only or args.only in c.category or args.only in c.what]
    if args.quick:
        selected = [c for i, c in enumerate(selected) if c.category in ("signal", "output") or i % 5 == 0]
    rows, tally = [], {name: {} for name, _ in builds}
    for i, case in enumerate(selected, 1):
        answers = []
        for name, programs in builds:
            verdict, answer = run_case(case, programs, FIX, os.path.join(work, name), i)
            tally[name][verdict] = tally[name].get(verdict, 0) + 1
            answers.append((verdict, answer))
        rows.append((i, case, answers))
        print("%3d %-14s %-55s %s" % (i, case.category, case.what[:55], "  ->  ".join(v for v, _ in answers)), flush=True)
    header = "| # | what | input | " + " | ".join(f"{n}" for n, _ in builds) + " |\n|---|---|---|" + "---|" * len(builds) + "\n"
    lines = [f"| {i} | {c.category} | {c.what} | " + " | ".join(f"**{v}**: {a}" for v, a in ans) + " |" for i, c, ans in rows]
    summary = "\n".join(f"{name}: " + ", ".join(f"{k} {v}" for k, v in sorted(t.items())) for name, t in tally.items())
    if args.table:
        with open(args.table, "w") as f:
            f.write(header + "\n".join(lines) + "\n\n" + summary + "\n")
    print(summary)
    shutil.rmtree(work, ignore_errors=True)
    bad = sum(v for k, v in tally[builds[-1][0]].items() if k not in ("ok", "skipped"))
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
