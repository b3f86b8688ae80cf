#!/usr/bin/python3
"""Run.samples reading 10^6 samples of one channel into NumPy.

The run: a short `bosfuse demo` run whose first thermocouple gets 10^6 more
samples (ok, one every 10 ms after its last, status 0) written into its
store with Python's sqlite3, in the store's own schema; the samples are
then read back with bosfuse.Run(...).samples(channel). Median of --repeat
reads, each in a fresh Run, wall and CPU time (the process's: on a shared,
loaded machine the wall time is mostly waiting for a core). Debian packages: python3-numpy.

  PYTHONPATH=build/python python3 python/bench/bench_run_samples.py --bosfuse build/bosfuse
"""
import argparse
import pathlib
import sqlite3
import statistics
import subprocess
import tempfile
import time

import bosfuse


def make_run(bosfuse_exe, folder, count):
    subprocess.run([bosfuse_exe, "demo", "-o", folder, "--experiment-time", "20s", "--speed", "100", "--seed", "5"],
                   check=True, capture_output=True)
    run_dir = next(p for p in pathlib.Path(folder).iterdir() if (p / "run.sqlite").exists())
    channel = bosfuse.Run(run_dir).channels[0]
    db = sqlite3.connect(run_dir / "run.sqlite")
    (last,) = db.execute("SELECT MAX(t_ns) FROM samples WHERE channel_id = ?", (channel.id,)).fetchone()
    existing = db.execute("SELECT COUNT(*) FROM samples WHERE channel_id = ?", (channel.id,)).fetchone()[0]
    rows = ((channel.id, last + (k + 1) * 10_000_000, 20.0 + (k % 1000) * 1e-3, 0) for k in range(count - existing))
    db.executemany("INSERT INTO samples (channel_id, t_ns, value, status) VALUES (?, ?, ?, ?)", rows)
    db.commit()
    db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    db.close()
    return run_dir, channel.name


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bosfuse", required=True, help="the built executable, for the demo run")
    p.add_argument("--samples", type=int, default=1_000_000)
    p.add_argument("--repeat", type=int, default=5)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        run_dir, name = make_run(args.bosfuse, folder, args.samples)
        times, cpu = [], []
        for _ in range(args.repeat):
            run = bosfuse.Run(run_dir)
            start, start_cpu = time.perf_counter(), time.process_time()
            t_s, value, status = run.samples(name)
            times.append(time.perf_counter() - start)
            cpu.append(time.process_time() - start_cpu)
        assert len(t_s) == args.samples, len(t_s)
        print(f"{len(t_s)} samples of '{name}': median {statistics.median(times):.3f} s "
              f"({min(times):.3f}-{max(times):.3f}) over {args.repeat} reads; CPU median {statistics.median(cpu):.3f} s")


if __name__ == "__main__":
    main()
