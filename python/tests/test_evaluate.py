"""bosfuse.evaluate and bosfuse.Evaluator against the CLI's `evaluate`."""
import csv
import io
import threading
import time

import numpy as np
import pytest

import bosfuse
from conftest import run_cli
from images import pair, write_pgm

COLUMNS = ["x", "y", "u", "v", "valid", "flag", "peak_ratio", "sigma_u", "sigma_v"]
DECIMALS = {"x": 1, "y": 1, "u": 5, "v": 5, "peak_ratio": 3, "sigma_u": 5, "sigma_v": 5}


def read_cli_csv(text):
    rows = list(csv.DictReader(io.StringIO(text)))
    assert rows and list(rows[0].keys()) == COLUMNS
    return rows


def assert_field_equals_csv(field, rows, shape):
    assert field.shape == shape and len(rows) == shape[0] * shape[1]
    for name, decimals in DECIMALS.items():
        printed = np.array([float(r[name]) for r in rows]).reshape(shape)
        np.testing.assert_allclose(getattr(field, name), printed, rtol=0, atol=0.5 * 10.0 ** -decimals + 1e-12,
                                   err_msg=name)
    assert np.array_equal(field.valid, np.array([r["valid"] == "1" for r in rows]).reshape(shape))
    names = np.array([bosfuse.FLAG_NAMES[c] for c in field.flag.ravel()])
    assert list(names) == [r["flag"] for r in rows]


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    ref, meas = pair()
    d = tmp_path_factory.mktemp("pair")
    write_pgm(d / "ref.pgm", ref)
    write_pgm(d / "meas.pgm", meas)
    return ref, meas, d


def test_arrays_equal_the_cli_csv(images):
    ref, meas, d = images
    rows = read_cli_csv(run_cli("evaluate", d / "ref.pgm", d / "meas.pgm", "--window", 16, "--step", 8))
    field = bosfuse.evaluate(ref, meas, window=16, step=8)
    ny = len({r["y"] for r in rows})
    assert_field_equals_csv(field, rows, (ny, len(rows) // ny))
    inner = field.valid
    assert inner.sum() > 0.8 * inner.size
    assert abs(np.median(field.u[inner]) - 0.4) < 0.05 and abs(np.median(field.v[inner]) + 0.7) < 0.05


def test_options_and_paths_equal_the_cli(images):
    ref, meas, d = images
    args = ["--window", 24, "--step", 12, "--passes", 2, "--roi", "8,8,120,100", "--subpixel", "gauss3"]
    rows = read_cli_csv(run_cli("evaluate", d / "ref.pgm", d / "meas.pgm", *args))
    field = bosfuse.evaluate(d / "ref.pgm", str(d / "meas.pgm"),
                             settings={"window": 24, "passes": 2}, step=12, roi=(8, 8, 120, 100), subpixel="gauss3")
    ny = len({r["y"] for r in rows})
    assert_field_equals_csv(field, rows, (ny, len(rows) // ny))


def test_probes_equal_the_cli(images):
    ref, meas, d = images
    rows = read_cli_csv(run_cli("evaluate", d / "ref.pgm", d / "meas.pgm", "--probe", "40,50", "--probe", "100.5,70"))
    field = bosfuse.evaluate(ref, meas, probes=[(40, 50), (100.5, 70)])
    assert_field_equals_csv(field, rows, (1, 2))


def test_evaluator_keeps_its_reference(images):
    ref, meas, _ = images
    evaluator = bosfuse.Evaluator(ref, window=16, step=8)
    once = bosfuse.evaluate(ref, meas, window=16, step=8)
    for _ in range(2):
        again = evaluator.process(meas)
        np.testing.assert_array_equal(again.u, once.u)
        np.testing.assert_array_equal(again.v, once.v)
    probed = evaluator.process(meas, probes=[(40, 50)])
    assert probed.shape == (1, 1) and probed.valid[0, 0]


def test_uint16_and_float32_give_the_uint8_field(images):
    ref, meas, _ = images
    base = bosfuse.evaluate(ref, meas)
    as16 = bosfuse.evaluate(ref.astype(np.uint16) * 257, meas.astype(np.uint16) * 257)
    as32 = bosfuse.evaluate((ref / 255).astype(np.float32), (meas / 255).astype(np.float32))
    for other in (as16, as32):
        np.testing.assert_allclose(other.u, base.u, atol=1e-4)


def test_gil_released_while_evaluating():
    ref, meas = pair(rows=1024, cols=1024)
    counted = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set() and n < 10_000_000:
            n += 1
            if n % 1000 == 0:
                counted.append(time.perf_counter())

    thread = threading.Thread(target=count)
    thread.start()
    time.sleep(0.01)
    start = time.perf_counter()
    bosfuse.evaluate(ref, meas, window=16, step=4)
    end = time.perf_counter()
    done.set()
    thread.join(timeout=30)
    during = [t for t in counted if start < t < end]
    assert end - start > 0.05, "the evaluation was too short to tell"
    # With the GIL held the counting thread would make no progress at all
    # during the call; released, it counts all along.
    assert len(during) > 10, f"{len(during)} counts in {end - start:.3f} s"
