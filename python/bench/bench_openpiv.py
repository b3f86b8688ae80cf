#!/usr/bin/python3
"""bosfuse.evaluate against OpenPIV-python's windef (multi-pass, window
deformation) on the same synthetic pair, in one Python process.

Debian 12 packages it needs: python3-numpy python3-scipy python3-skimage
python3-imageio python3-natsort python3-tqdm (OpenPIV itself is pure Python:
give its source folder, e.g. a `git archive` of OpenPIV/openpiv-python, with
--openpiv). Debian's imageio 2.4 has no `imageio.v3`, which openpiv.tools
imports for file I/O; this script aliases imageio's imread/imwrite there (the
benchmark passes arrays, no file is read). The checkout has no package
metadata, so its version reads as the folder's.

The pair: a particle-like image (Gaussian dots of 1.2 px σ, an exact
rendering, no interpolation) and the same dots moved by a smooth plume-like
field, u = A·exp(-r²/2s²) radially outward, so the error is each method's own.
Both evaluate windows of 32 then 16 px on an 8 px grid (two passes with
deformation); the error is the RMS of (u, v) − truth at the final grid's
nodes at least 24 px inside the image that each method reports valid (OpenPIV:
every node, as it replaces outliers). Times are medians of --repeat runs.

  PYTHONPATH=build/python python3 python/bench/bench_openpiv.py --openpiv /tmp/openpiv-python-helper
"""
import argparse
import importlib.metadata
import statistics
import sys
import time
import types

import numpy as np


def render(xs, ys, size, sigma=1.2, grey=None, rows=None):
    """Gaussian dots at (xs, ys) on a (rows or size, size) image, exactly sampled."""
    rows = rows or size
    image = np.zeros(rows * size)
    ix, iy = np.floor(xs).astype(int), np.floor(ys).astype(int)
    for dy in range(-3, 5):
        for dx in range(-3, 5):
            px, py = ix + dx, iy + dy
            keep = (px >= 0) & (px < size) & (py >= 0) & (py < rows)
            w = np.exp(-((px - xs) ** 2 + (py - ys) ** 2) / (2 * sigma ** 2)) * grey
            image += np.bincount(py[keep] * size + px[keep], weights=w[keep], minlength=rows * size)
    return image.reshape(rows, size)


def displacement(x, y, size, amplitude):
    cx = cy = size / 2
    s = size / 8
    r2 = (x - cx) ** 2 + (y - cy) ** 2
    g = amplitude * np.exp(-r2 / (2 * s * s)) / s
    return g * (x - cx), g * (y - cy)


def synthetic_pair(size, amplitude, seed=1, rows=None):
    """(reference, measurement) uint8, (rows or size) x size px."""
    rows = rows or size
    rng = np.random.default_rng(seed)
    n = int(size * rows * 0.06)
    xs, ys = rng.uniform(-4, size + 4, n), rng.uniform(-4, rows + 4, n)
    grey = rng.uniform(0.5, 1.0, n)
    # The measurement's dot is where the reference's moved: (x + u, y + v) at the
    # dot's own position (a feature at (x, y) appears at (x + u, y + v)).
    u, v = displacement(xs, ys, size, amplitude)
    a, b = render(xs, ys, size, grey=grey, rows=rows), render(xs + u, ys + v, size, grey=grey, rows=rows)
    scale = 230 / max(a.max(), b.max())
    noise = lambda img: np.clip(np.rint(img * scale + 15 + rng.normal(0, 2, img.shape)), 0, 255).astype(np.uint8)
    return noise(a), noise(b)


def rms_error(x, y, u, v, valid, size, amplitude, margin=24):
    inside = (x >= margin) & (x <= size - 1 - margin) & (y >= margin) & (y <= size - 1 - margin) & valid
    tu, tv = displacement(x, y, size, amplitude)
    err = np.hypot(u - tu, v - tv)[inside]
    return float(np.sqrt(np.mean(err ** 2))), int(inside.sum())


def import_openpiv(folder):
    import imageio
    v3 = types.ModuleType("imageio.v3")
    v3.imread, v3.imwrite = imageio.imread, imageio.imwrite
    sys.modules.setdefault("imageio.v3", v3)
    real = importlib.metadata.version
    importlib.metadata.version = lambda name: folder if name == "OpenPIV" else real(name)
    sys.path.insert(0, folder)
    from openpiv import settings, windef
    importlib.metadata.version = real
    return settings, windef


def openpiv_run(windef, settings_mod, a, b):
    s = settings_mod.PIVSettings()
    s.windowsizes, s.overlap, s.num_iterations = (32, 16), (16, 8), 2
    s.show_plot = s.save_plot = False
    x, y, u, v, flags = windef.simple_multipass(a.astype(np.float64), b.astype(np.float64), s)
    # Back to image coordinates (simple_multipass returns y up, v up).
    return x, y[::-1, :], u, -v, np.ones_like(u, dtype=bool)


def timed(repeat, call):
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--openpiv", required=True, help="folder holding the openpiv package's source")
    p.add_argument("--size", type=int, default=1024, help="image side, px")
    p.add_argument("--amplitude", type=float, default=3.0, help="largest displacement scale, px")
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args()
    import bosfuse
    settings_mod, windef = import_openpiv(args.openpiv)
    a, b = synthetic_pair(args.size, args.amplitude)
    t_b, f = timed(args.repeat * 3, lambda: bosfuse.evaluate(a, b, window=16, step=8, passes=2, first_window=32))
    e_b, n_b = rms_error(f.x, f.y, f.u, f.v, f.valid, args.size, args.amplitude)
    t_o, (x, y, u, v, ok) = timed(args.repeat, lambda: openpiv_run(windef, settings_mod, a, b))
    e_o, n_o = rms_error(x, y, u, v, ok, args.size, args.amplitude)
    print(f"pair {args.size}x{args.size} px, displacement up to {args.amplitude * np.exp(-0.5):.2f} px")
    print(f"bosfuse.evaluate  median {t_b:.3f} s  RMS error {e_b:.4f} px over {n_b} nodes")
    print(f"openpiv.windef    median {t_o:.3f} s  RMS error {e_o:.4f} px over {n_o} nodes")
    print(f"bosfuse is {t_o / t_b:.0f}x faster, error {'equal or lower' if e_b <= e_o else 'HIGHER'}")


if __name__ == "__main__":
    main()
