#!/usr/bin/python3
"""The Python module's call overhead: bosfuse.evaluate on a 16 MP pair
(4928x3264, uint8) from NumPy arrays (IW 16, step 8, 3 passes, max shift
2 px), its wall time in Python against the library's own time for the same
evaluation (Field.seconds, measured inside the C++ evaluator). What the
call adds: converting the options, wrapping the arrays (not copied), the
pair's checks, making the nine result arrays. The pair is bench_openpiv.py's
(Gaussian dots moved by a plume-like field). Medians of --rounds rounds of
three calls. Debian packages: python3-numpy.

  PYTHONPATH=build/python python3 python/bench/bench_overhead.py
"""
import argparse
import os
import statistics
import sys
import time

import bosfuse

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_openpiv import synthetic_pair  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--rounds", type=int, default=5)
    args = p.parse_args()
    reference, measurement = synthetic_pair(4928, 3.0, rows=3264)
    wall, own, cpu = [], [], []
    for _ in range(args.rounds * 3):
        start, start_cpu = time.perf_counter(), time.process_time()
        field = bosfuse.evaluate(reference, measurement, window=16, step=8, passes=3, max_shift=2)
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
        own.append(field.seconds)
    w, o = statistics.median(wall), statistics.median(own)
    print(f"pair {reference.shape[1]}x{reference.shape[0]} {reference.dtype}, field {field.shape[1]}x{field.shape[0]}, "
          f"{int(field.valid.sum())} valid")
    print(f"bosfuse.evaluate from NumPy: median {w * 1e3:.0f} ms wall ({min(wall) * 1e3:.0f}-{max(wall) * 1e3:.0f}), "
          f"{statistics.median(cpu) * 1e3:.0f} ms CPU, over {len(wall)} calls")
    print(f"the library's own time (Field.seconds): median {o * 1e3:.0f} ms")
    print(f"the call adds {100 * (w / o - 1):+.1f} % (median of the per-call ratios "
          f"{100 * (statistics.median([a / b for a, b in zip(wall, own)]) - 1):+.1f} %)")


if __name__ == "__main__":
    main()
