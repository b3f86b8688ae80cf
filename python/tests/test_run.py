"""bosfuse.Run against `bosfuse export --csv` of a short demo run."""
import csv
import hashlib
import io
import shutil
import sqlite3

import numpy as np
import pytest

import bosfuse
from conftest import DEMO_SPEED, run_cli


def test_samples_equal_the_export(demo_run):
    rows = list(csv.DictReader(io.StringIO(run_cli("export", demo_run, "--csv"))))
    run = bosfuse.Run(demo_run)
    assert run.status == "complete" and run.time_scale == DEMO_SPEED
    assert run.channels and run.devices and run.frames and run.events
    for channel in run.channels:
        column = f"{channel.name} [{channel.unit}]"
        if channel.kind == "thermocouple":  # the module's register step (schema 6)
            assert channel.resolution == pytest.approx(1370 / 65535)
        expected = [(float(r["t_s"]), float(r[column])) for r in rows if r[column] != ""]
        t_s, value, status = run.samples(channel)
        ok = status == 0
        assert ok.sum() == len(expected)
        np.testing.assert_allclose(t_s[ok], [e[0] for e in expected], atol=5e-7 + 1e-9, rtol=0)  # printed to 6 decimals
        # The export prints each value at its channel's resolution (the
        # demo's adam-6018 steps by 1370/65535 °C: two decimals, so within
        # 0.005 °C); the run keeps the full doubles.
        np.testing.assert_allclose(value[ok], [e[1] for e in expected], atol=0.005 + 1e-9, rtol=0)
        assert np.isnan(value[~ok]).all()
        same = run.samples(channel.name)
        np.testing.assert_array_equal(same[0], t_s)
    assert run.frames[0].path.endswith(".png") and all(f.t_s >= 0 for f in run.frames)
    with pytest.raises(KeyError, match="no channel 'nope'"):
        run.samples("nope")


def test_a_dead_loggers_run_reads_as_interrupted_unwritten(demo_run, tmp_path):
    copy = tmp_path / "run"
    shutil.copytree(demo_run, copy)
    db = sqlite3.connect(copy / "run.sqlite", isolation_level=None)
    db.execute("UPDATE runs SET status = 'running', ended_ns = NULL")
    db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    db.close()
    before = hashlib.sha256((copy / "run.sqlite").read_bytes()).hexdigest()
    run = bosfuse.Run(copy)
    assert run.status == "interrupted"
    assert len(run.samples(run.channels[0])[0]) > 0
    del run
    assert hashlib.sha256((copy / "run.sqlite").read_bytes()).hexdigest() == before


def test_not_a_run_is_a_storage_error(tmp_path):
    with pytest.raises(bosfuse.StorageError, match="holds no bosfuse run"):
        bosfuse.Run(tmp_path)
