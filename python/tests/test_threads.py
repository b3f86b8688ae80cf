"""Evaluations from several Python threads at once: each gives what it gives
alone, and none waits on another (the GIL is released only around the
library's own C++). The threads run in a child interpreter with a timeout,
so a hang fails the test instead of holding the suite."""
import os
import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    from concurrent.futures import ThreadPoolExecutor
    import threading
    import numpy as np
    import bosfuse
    from images import pair

    pairs = [pair(rows=384, cols=448, shift=(0.2 * k, -0.3 * k), seed=k) for k in range(1, 7)]
    alone = [bosfuse.evaluate(r, m, window=16, step=8) for r, m in pairs]
    local = threading.local()

    def by_evaluator(k):
        if not hasattr(local, "evaluator"):
            local.evaluator = bosfuse.Evaluator(pairs[0][0], window=16, step=8)
        return local.evaluator.process(pairs[0][1] if k % 2 else pairs[0][0])

    shared = bosfuse.Evaluator(pairs[1][0], window=16, step=8)
    t = np.linspace(0, 60, 61)
    temperature = 20 + 40 * np.exp(-t / 25)
    with ThreadPoolExecutor(max_workers=3) as pool:
        at_once = [pool.submit(bosfuse.evaluate, r, m, window=16, step=8) for r, m in pairs]
        evaluators = [pool.submit(by_evaluator, k) for k in range(6)]
        shared_runs = [pool.submit(shared.process, pairs[1][1]) for _ in range(4)]
        fits = [pool.submit(bosfuse.fit_newton, t, temperature) for _ in range(3)]
        for f, a in zip(at_once, alone):
            got = f.result(timeout=60)
            assert np.array_equal(got.u, a.u) and np.array_equal(got.v, a.v) and np.array_equal(got.flag, a.flag)
        self_field = bosfuse.evaluate(pairs[0][0], pairs[0][0], window=16, step=8)
        for k, f in enumerate(evaluators):
            want = alone[0] if k % 2 else self_field
            assert np.array_equal(f.result(timeout=60).u, want.u)
        for f in shared_runs:
            assert np.array_equal(f.result(timeout=60).u, alone[1].u)
        taus = {round(f.result(timeout=60)["parameters"]["tau_s"]["value"], 9) for f in fits}
        assert len(taus) == 1
    print("same")
""")


def test_evaluations_from_threads_at_once_equal_sequential_ones():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([os.path.dirname(__file__), env.get("PYTHONPATH", "")])
    result = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "same"


# Frames given as paths to an Evaluator per thread, as docs/PYTHON.md's
# thread pool does, in an interpreter that has made no array before: the
# first arrays are made by two threads at once. (This hung: NumPy's C API was
# looked up on first use into a function-local static of pybind11's, the
# lookup's import let go of the GIL, and the other thread then waited on the
# static's guard holding it.)
PATHS = textwrap.dedent("""
    import sys, threading
    from concurrent.futures import ThreadPoolExecutor
    import bosfuse
    reference, frames = sys.argv[1], sys.argv[2:]
    local = threading.local()

    def field_of(path):
        if not hasattr(local, "evaluator"):
            local.evaluator = bosfuse.Evaluator(reference, window=16, step=8)
        return local.evaluator.process(path)

    with ThreadPoolExecutor(max_workers=2) as pool:
        fields = [pool.submit(field_of, p) for p in frames] + [pool.submit(bosfuse.evaluate, reference, p, window=16, step=8) for p in frames]
        us = [f.result(timeout=60).u.tolist() for f in fields]
    n = len(frames)
    assert us[:n] == us[n:], "an Evaluator's field differs from evaluate's"
    print("same")
""")


def test_frames_from_paths_in_a_thread_pool(tmp_path):
    from images import pair, write_pgm
    paths = []
    for k in range(4):
        ref, meas = pair(rows=256, cols=320, shift=(0.1 * k, 0.2), seed=1)
        write_pgm(tmp_path / f"frame{k}.pgm", meas)
    write_pgm(tmp_path / "reference.pgm", ref)
    paths = [str(tmp_path / f"frame{k}.pgm") for k in range(4)]
    result = subprocess.run([sys.executable, "-c", PATHS, str(tmp_path / "reference.pgm"), *paths],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "same"
