#!/usr/bin/env python3
"""bosfuse against OpenPIV on the same synthetic pairs, in one run.

Debian 12 packages (apt-get install): python3-numpy python3-scipy python3-skimage
python3-imageio python3-natsort python3-tqdm. OpenPIV itself is not packaged:
give its source folder (openpiv-python, pure Python) with --openpiv, e.g. a
checkout of https://github.com/OpenPIV/openpiv-python.

    ninja -C build write_bench_pairs bosfuse
    python3 bench/openpiv_compare.py --build build --openpiv /tmp/openpiv [--repeat 3]

It writes issue 30's pairs with build/bench/write_bench_pairs (the very
pairs bos_bench evaluates: bench/bench_scenes.h), evaluates each with
`bosfuse evaluate` (its defaults, and each --preprocess) and with OpenPIV's
windef multipass at its defaults (PIVSettings(): windows 64, 32, 16 with
50 % overlap, FFT correlation, Gaussian peak fit, symmetric deformation,
validation and replacement; --openpiv-settings runs it again with some
changed), and prints the RMS error of the vector magnitude error over the
vectors each calls valid, more than one final window (16 px) from the
border, its bias and random parts, with the time each took (median of
--repeat).
"""

import argparse
import csv
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

import imageio
import numpy as np


def rms_error(xs, ys, us, vs, size, shift, border_px=16):
    """RMS of |(u, v) - truth| over the vectors more than a window from the
    border, their count, and the bias: |mean (u, v) - truth|."""
    sum_sq, n, sum_u, sum_v = 0.0, 0, 0.0, 0.0
    for x, y, u, v in zip(xs, ys, us, vs):
        if x < border_px or y < border_px or x >= size[1] - border_px or y >= size[0] - border_px:
            continue
        sum_sq += (u - shift[0]) ** 2 + (v - shift[1]) ** 2
        sum_u += u - shift[0]
        sum_v += v - shift[1]
        n += 1
    if not n:
        return float("nan"), 0, float("nan")
    return math.sqrt(sum_sq / n), n, math.hypot(sum_u / n, sum_v / n)


def run_bosfuse(binary, a, b, size, shift, extra):
    with tempfile.NamedTemporaryFile(suffix=".csv") as out:
        start = time.monotonic()
        subprocess.run([binary, "evaluate", a, b, "--out", out.name, *extra], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        seconds = time.monotonic() - start
        with open(out.name, newline="") as f:
            rows = [r for r in csv.DictReader(f) if r["valid"] in ("1", "true")]
    xs = [float(r["x"]) for r in rows]
    ys = [float(r["y"]) for r in rows]
    us = [float(r["u"]) for r in rows]
    vs = [float(r["v"]) for r in rows]
    rms, n, bias = rms_error(xs, ys, us, vs, size, shift)
    return rms, n, seconds, bias


def run_openpiv(a, b, size, shift, overrides=None):
    from openpiv import windef
    from openpiv.settings import PIVSettings

    frame_a = imageio.imread(a).astype(np.float64)
    frame_b = imageio.imread(b).astype(np.float64)
    settings = PIVSettings()  # its defaults: windows (64, 32, 16), overlap (32, 16, 8), 3 iterations
    for key, value in (overrides or {}).items():
        setattr(settings, key, tuple(value) if isinstance(value, list) else value)
    settings.num_iterations = len(settings.windowsizes)
    # windef.simple_multipass's steps, at PIVSettings()'s three passes (simple_multipass
    # itself changes the defaults to two passes when given no settings).
    start = time.monotonic()
    x, y, u, v, s2n = windef.first_pass(frame_a, frame_b, settings)
    u = np.ma.array(u, mask=np.zeros_like(u, dtype=bool))
    v = np.ma.array(v, mask=np.zeros_like(v, dtype=bool))
    flags = windef.validation.typical_validation(u, v, s2n, settings)
    u, v = windef.filters.replace_outliers(u, v, flags)
    for i in range(1, settings.num_iterations):
        x, y, u, v, grid_mask, flags = windef.multipass_img_deform(frame_a, frame_b, i, x, y, u, v, settings)
    seconds = time.monotonic() - start
    # Image coordinates (x right, y down: before windef's transform_coordinates,
    # this version's v is positive downwards); the last pass's outliers left out.
    u = np.ma.filled(u, np.nan)
    v = np.ma.filled(v, np.nan)
    keep = np.isfinite(u) & np.isfinite(v) & ~np.asarray(flags, dtype=bool)
    rms, n, bias = rms_error(x[keep], y[keep], u[keep], v[keep], size, shift)
    return rms, n, seconds, bias


def use_openpiv_source(folder):
    """openpiv importable from its source folder. Its __init__ asks the installed
    package's metadata for its version; a source folder has none, so the
    version is read from its pyproject.toml."""
    import importlib
    import importlib.metadata
    import re

    sys.path.insert(0, os.path.abspath(folder))
    # openpiv.tools imports imageio.v3 (imageio 2.16+); Debian 12 has 2.4.1. Only
    # its file reading needs it, which this script does itself: the old API stands in.
    try:
        importlib.import_module("imageio.v3")
    except ImportError:
        import types

        v3 = types.ModuleType("imageio.v3")
        v3.imread, v3.imwrite = imageio.imread, imageio.imwrite
        sys.modules["imageio.v3"] = v3
    try:
        importlib.metadata.version("OpenPIV")
        return
    except importlib.metadata.PackageNotFoundError:
        pass
    with open(os.path.join(folder, "pyproject.toml")) as f:
        found = re.search(r'^version\s*=\s*"([^"]+)"', f.read(), re.M)
    source_version = found.group(1) if found else "source"
    installed = importlib.metadata.version
    importlib.metadata.version = lambda name: source_version if name == "OpenPIV" else installed(name)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default="build", help="bosfuse's build folder")
    parser.add_argument("--openpiv", required=True, help="openpiv-python's source folder (holds openpiv/)")
    parser.add_argument("--repeat", type=int, default=1, help="times each evaluation is timed (median)")
    parser.add_argument("--pairs", default=None, help="folder for the pairs (default: a temporary one)")
    parser.add_argument("--openpiv-settings", action="append", default=[], metavar="JSON",
                        help='also run OpenPIV with these PIVSettings changed, e.g. \'{"deformation_method": '
                             '"second image"}\' or \'{"windowsizes": [32, 16], "overlap": [16, 8]}\' (repeatable)')
    args = parser.parse_args()
    use_openpiv_source(args.openpiv)
    import openpiv

    folder = args.pairs or tempfile.mkdtemp(prefix="bosfuse-pairs-")
    subprocess.run([os.path.join(args.build, "bench", "write_bench_pairs"), folder], check=True)
    with open(os.path.join(folder, "pairs.json")) as f:
        pairs = json.load(f)
    binary = os.path.join(args.build, "bosfuse")
    variants = [("bosfuse", []), ("bosfuse --preprocess normalize", ["--preprocess", "normalize"]),
                ("bosfuse --preprocess highpass", ["--preprocess", "highpass"]),
                ("bosfuse --preprocess minmax", ["--preprocess", "minmax"]),
                ("bosfuse --preprocess denoise", ["--preprocess", "denoise"]),
                # One pass at the final window, as OpenPIV's 64 → 32 → 16 has.
                ("bosfuse --first-window 32 --passes 2", ["--first-window", "32", "--passes", "2"]),
                ("bosfuse --first-window 64", ["--first-window", "64"]),
                ("bosfuse --preprocess denoise --first-window 64", ["--preprocess", "denoise", "--first-window", "64"])]
    print(f"OpenPIV {getattr(openpiv, '__version__', '?')} from {args.openpiv}, numpy {np.__version__}; "
          f"pairs in {folder}")
    # The bias is each pair's |mean error| (RMS over a group's pairs); the
    # random part the rest of the RMS error: sqrt(RMS² − bias²).
    print("| pair | program | RMS error (px) | bias (px) | random (px) | vectors compared | s (median) |")
    print("|---|---|---|---|---|---|---|")
    # The low-contrast pairs by noise: the three shifts pooled, as bos_bench's BM_LowContrastTenBit.
    groups = {}
    for p in pairs:
        groups.setdefault(p["name"].rsplit("_", 1)[0] if p["name"].startswith("lowcontrast") else p["name"], []).append(p)
    for group, members in groups.items():
        programs = variants if group.startswith("lowcontrast") else variants[:1]
        programs = programs + [("OpenPIV windef, defaults", None)]
        if group.startswith("lowcontrast"):
            programs = programs + [(f"OpenPIV windef, {o}", json.loads(o)) for o in args.openpiv_settings]
        for label, extra in programs:
            sum_sq, sum_bias_sq, n_all, times = 0.0, 0.0, 0, []
            for p in members:
                a, b = os.path.join(folder, p["a"]), os.path.join(folder, p["b"])
                size = imageio.imread(a).shape
                shift = (p["u_px"], p["v_px"])
                runs = [run_bosfuse(binary, a, b, size, shift, extra) if isinstance(extra, list)
                        else run_openpiv(a, b, size, shift, extra) for _ in range(args.repeat)]
                rms, n, _, bias = runs[0]
                sum_sq += rms * rms * n
                sum_bias_sq += bias * bias * n
                n_all += n
                times.append(statistics.median(r[2] for r in runs))
            rms_all = math.sqrt(sum_sq / n_all) if n_all else float("nan")
            bias_all = math.sqrt(sum_bias_sq / n_all) if n_all else float("nan")
            random_all = math.sqrt(max(rms_all ** 2 - bias_all ** 2, 0.0))
            print(f"| {group} | {label} | {rms_all:.4f} | {bias_all:.4f} | {random_all:.4f} | {n_all} | "
                  f"{sum(times):.2f} |")


if __name__ == "__main__":
    main()
