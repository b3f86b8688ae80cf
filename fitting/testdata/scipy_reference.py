#!/usr/bin/python3
"""Independent reference for bosfuse's Newton fit: scipy.optimize.curve_fit.

Fits T(t) = T_amb + (T0 - T_amb) * exp(-k t) to newton_reference.csv (columns
t_s, T_c) three ways and writes parameters and standard errors to
newton_reference_scipy.json, which fitting/newton_fit_reference_test.cc
compares with fit_newton():

  free            ambient free, errors scaled by s^2 = SSR/(n-p)  (absolute_sigma=False)
  fixed_ambient   T_amb held at FIXED_AMBIENT_C, errors scaled
  absolute_sigma  ambient free, sigma = KNOWN_SIGMA_C, absolute_sigma=True

The data set itself was made once with `--make-data` (a seeded Python
random.Random, no numpy, so it never changes) and is committed; the fit
reads it back from the CSV so both sides see the same decimal values.

How it was run (Debian 12, 2026-11-23):
  apt-get install -y python3-scipy        # not a project dependency
  cd fitting/testdata && /usr/bin/python3 scipy_reference.py   # Debian python3 3.11, scipy 1.10.1
It uses the analytic Jacobian and tight tolerances so the reference is
limited by double precision, not by finite differences or early stopping.
"""

import csv
import json
import math
import random
import sys

TRUE_K_PER_S = 0.0123
TRUE_T0_C = 78.4
TRUE_AMBIENT_C = 23.1
NOISE_C = 0.15
FIXED_AMBIENT_C = 23.0
KNOWN_SIGMA_C = 0.15


def make_data(path):
    """120 samples over ~3.3 time constants, slightly irregular spacing."""
    rng = random.Random(20261123)
    rows = []
    t = 0.0
    for _ in range(120):
        temperature = TRUE_AMBIENT_C + (TRUE_T0_C - TRUE_AMBIENT_C) * math.exp(-TRUE_K_PER_S * t)
        rows.append((t, temperature + rng.gauss(0.0, NOISE_C)))
        t += 2.25 + rng.uniform(-0.25, 0.25)
    with open(path, "w", newline="") as f:
        f.write("t_s,T_c\n")
        for t, temperature in rows:
            f.write(f"{t:.6f},{temperature:.6f}\n")


def read_data(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [float(r["t_s"]) for r in rows], [float(r["T_c"]) for r in rows]


def fit(t, y, fixed_ambient=None, sigma=None):
    import numpy as np
    from scipy.optimize import curve_fit

    t = np.asarray(t)
    y = np.asarray(y)
    tight = dict(xtol=1e-15, ftol=1e-15, gtol=1e-15, maxfev=10000)
    if fixed_ambient is None:
        def model(t, k, t0, amb):
            return amb + (t0 - amb) * np.exp(-k * t)

        def jac(t, k, t0, amb):
            e = np.exp(-k * t)
            return np.column_stack([-(t0 - amb) * t * e, e, 1.0 - e])

        p0 = [0.01, y[0], y[-1]]
        names = ["k_per_s", "t0_c", "ambient_c"]
    else:
        def model(t, k, t0):
            return fixed_ambient + (t0 - fixed_ambient) * np.exp(-k * t)

        def jac(t, k, t0):
            e = np.exp(-k * t)
            return np.column_stack([-(t0 - fixed_ambient) * t * e, e])

        p0 = [0.01, y[0]]
        names = ["k_per_s", "t0_c"]
    kwargs = {}
    if sigma is not None:
        kwargs = dict(sigma=np.full_like(y, sigma), absolute_sigma=True)
    popt, pcov = curve_fit(model, t, y, p0=p0, jac=jac, method="lm", **kwargs, **tight)
    errors = np.sqrt(np.diag(pcov))
    result = {name: {"value": float(v), "std_error": float(e)} for name, v, e in zip(names, popt, errors)}
    residuals = y - model(t, *popt)
    result["residual_rms_c"] = float(np.sqrt(np.mean(residuals**2)))
    return result


def main():
    if "--make-data" in sys.argv:
        make_data("newton_reference.csv")
    import scipy

    t, y = read_data("newton_reference.csv")
    reference = {
        "generator": f"scipy {scipy.__version__} curve_fit(method='lm'), analytic Jacobian, tolerances 1e-15",
        "points": len(t),
        "fixed_ambient_c": FIXED_AMBIENT_C,
        "known_sigma_c": KNOWN_SIGMA_C,
        "free": fit(t, y),
        "fixed_ambient": fit(t, y, fixed_ambient=FIXED_AMBIENT_C),
        "absolute_sigma": fit(t, y, sigma=KNOWN_SIGMA_C),
    }
    with open("newton_reference_scipy.json", "w") as f:
        json.dump(reference, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main()
