#!/usr/bin/python3
"""The Python module's call overhead: bosfuse.evaluate on the 16 MP pair
(4928x3264) from NumPy arrays against the C++ benchmark of the same call on
the same pixels (bench/bos_bench.cc, BM_FullFrame16MPPair:
pipeline::evaluate_image_pair, IW 16, step 8, 3 passes, max shift 2 px).

The C++ benchmark renders the pair and writes it (BOSFUSE_BENCH_PAIR_DIR);
this script reads it with bosfuse.read_image and evaluates it with the same
options. The two alternate, round after round, so a load that comes and goes
on the machine falls on both; the figures are the medians over all rounds.
Debian packages: python3-numpy (and the build's bos_bench).

  PYTHONPATH=build/python python3 python/bench/bench_overhead.py --bos-bench build/bench/bos_bench
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import bosfuse


def cpp_times(bos_bench, pair_dir):
    out = subprocess.run([bos_bench, "--benchmark_filter=BM_FullFrame16MPPair$", "--benchmark_format=json"],
                         capture_output=True, text=True, check=True, env={**os.environ, "BOSFUSE_BENCH_PAIR_DIR": pair_dir})
    runs = [b for b in json.loads(out.stdout)["benchmarks"] if b.get("run_type", "iteration") == "iteration"]
    return [b["real_time"] / 1e3 for b in runs]  # ms -> s, one per repetition (its mean over 3 iterations)


def python_round(reference, measurement):
    """The mean wall time of three evaluate() calls and the library's own time of the last."""
    times = []
    for _ in range(3):
        start = time.perf_counter()
        field = bosfuse.evaluate(reference, measurement, window=16, step=8, passes=3, max_shift=2)
        times.append(time.perf_counter() - start)
    return statistics.mean(times), field.seconds, field


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bos-bench", help="the built bench/bos_bench; without it the pair is made in NumPy "
                   "(bench_openpiv.py's dots) and compared with the library's own time only")
    p.add_argument("--rounds", type=int, default=5)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as pair_dir:
        cpp, py, inner = [], [], []
        if not args.bos_bench:
            sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
            from bench_openpiv import synthetic_pair
            reference, measurement = synthetic_pair(4928, 3.0, rows=3264)
        for k in range(args.rounds):
            if args.bos_bench:
                cpp += cpp_times(args.bos_bench, pair_dir)
                if k == 0:
                    reference = bosfuse.read_image(os.path.join(pair_dir, "reference.png"))
                    measurement = bosfuse.read_image(os.path.join(pair_dir, "measurement.png"))
            wall, own, field = python_round(reference, measurement)
            py.append(wall)
            inner.append(own)
    q, own = statistics.median(py), statistics.median(inner)
    print(f"pair {reference.shape[1]}x{reference.shape[0]} {reference.dtype}, field {field.shape[1]}x{field.shape[0]}, "
          f"{int(field.valid.sum())} valid")
    print(f"bosfuse.evaluate (NumPy)  median {q * 1e3:.0f} ms over {len(py)} rounds ({min(py) * 1e3:.0f}-{max(py) * 1e3:.0f})")
    print(f"  the library's own time (Field.seconds) median {own * 1e3:.0f} ms: the call adds {100 * (q / own - 1):+.1f} %")
    if cpp:
        c = statistics.median(cpp)
        print(f"C++ BM_FullFrame16MPPair  median {c * 1e3:.0f} ms over {len(cpp)} rounds "
              f"({min(cpp) * 1e3:.0f}-{max(cpp) * 1e3:.0f}): Python {100 * (q / c - 1):+.1f} %")


if __name__ == "__main__":
    main()
