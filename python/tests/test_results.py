"""What `bosfuse process` stored for a demo run, read through bosfuse.Run
(frame images, fields, probe series, fits, agreements), and
bosfuse.temperature_field against the temperature field process stored."""
import csv
import io
import json
import sqlite3
import tomllib

import numpy as np
import pytest

import bosfuse
from conftest import run_cli


def stored_rows(run_dir, kind):
    db = sqlite3.connect(f"file:{run_dir / 'run.sqlite'}?mode=ro", uri=True)
    rows = db.execute("SELECT frame_id, path FROM fields WHERE kind = ? ORDER BY frame_id", (kind,)).fetchall()
    db.close()
    return rows


def read_csv_grid(path, columns):
    rows = list(csv.DictReader(open(path)))
    xs = sorted({float(r["x"]) for r in rows})
    ys = sorted({float(r["y"]) for r in rows})
    shape = (len(ys), len(xs))
    assert len(rows) == shape[0] * shape[1]
    out = {}
    for c in columns:
        out[c] = np.array([r[c] for r in rows]).reshape(shape)
    return out, shape


def frame_index(run, frame_id):
    return [f.id for f in run.frames].index(frame_id)


def test_frame_image_is_the_stored_file_at_its_depth(demo_run):
    run = bosfuse.Run(demo_run)
    for i, frame in enumerate(run.frames[:3]):
        image = run.frame_image(i)
        assert image.shape[:2] == (frame.height_px, frame.width_px)
        assert image.dtype == (np.uint16 if frame.bit_depth > 8 else np.uint8)
        np.testing.assert_array_equal(image, bosfuse.read_image(frame.path))
    np.testing.assert_array_equal(run.frame_image(-1), run.frame_image(len(run.frames) - 1))
    with pytest.raises(IndexError, match="frames"):
        run.frame_image(len(run.frames))


def test_field_is_the_stored_csv(demo_run):
    run = bosfuse.Run(demo_run)
    rows = stored_rows(demo_run, "displacement")
    assert rows
    frame_id, path = rows[-1]
    field = run.field(frame_index(run, frame_id))
    grid, shape = read_csv_grid(demo_run / path, ["x", "y", "u", "v", "valid", "flag", "sigma_u"])
    assert field.shape == shape
    for name in ("x", "y", "u", "v", "sigma_u"):
        np.testing.assert_array_equal(getattr(field, name), grid[name].astype(float), err_msg=name)
    np.testing.assert_array_equal(field.valid, grid["valid"] == "1")
    assert [bosfuse.FLAG_NAMES[c] for c in field.flag.ravel()] == list(grid["flag"].ravel())
    reference = [i for i, f in enumerate(run.frames) if f.id not in {r[0] for r in rows}]
    if reference:
        with pytest.raises(bosfuse.NoStoredFields, match="no stored displacement field"):
            run.field(reference[0])


def test_temperature_field_equals_the_stored_one(demo_run):
    run = bosfuse.Run(demo_run)
    geometry = tomllib.loads(run.config).get("geometry", {})
    displacement = dict(stored_rows(demo_run, "displacement"))
    temperature = stored_rows(demo_run, "temperature")
    assert temperature
    frame_id, path = temperature[-1]
    solved = bosfuse.temperature_field(run.field(frame_index(run, frame_id)), geometry)
    grid, shape = read_csv_grid(demo_run / path, ["x", "y", "temperature_c", "measured"])
    assert solved.temperature_c.shape == shape and frame_id in displacement
    np.testing.assert_array_equal(solved.x, grid["x"].astype(float))
    np.testing.assert_array_equal(solved.measured, grid["measured"] == "1")
    stored = grid["temperature_c"].astype(float)
    # process solved the unrounded field, this the stored one (u, v to 5 decimals).
    np.testing.assert_allclose(solved.temperature_c, stored, rtol=0, atol=2e-3)
    assert np.isnan(solved.sigma_c).all()
    with_sigma = bosfuse.temperature_field(run.field(frame_index(run, frame_id)), geometry, uncertainty=True)
    np.testing.assert_array_equal(with_sigma.temperature_c, solved.temperature_c)
    assert (np.isfinite(with_sigma.sigma_c) == (with_sigma.measured & with_sigma.physical)).all()
    assert "°C" in solved.summary or "nodes" in solved.summary


def test_temperature_field_geometry_errors_name_the_key(demo_run):
    field = bosfuse.Run(demo_run).field(-1)
    with pytest.raises(bosfuse.ConfigError, match="z_d_mm"):
        bosfuse.temperature_field(field, {"z_d_mm": 0.5})
    with pytest.raises(bosfuse.ConfigError, match="open_edges"):
        bosfuse.temperature_field(field, {"open_edges": ["up"]})
    hotter = bosfuse.temperature_field(field, {"ambient_temperature_c": 30.0, "open_edges": ["top"]})
    assert np.nanmin(hotter.temperature_c) > 25


def test_probe_series_equal_the_export(demo_run):
    run = bosfuse.Run(demo_run)
    rows = list(csv.DictReader(io.StringIO(run_cli("export", demo_run, "--probes"))))
    series = run.probe_series()
    assert series and sum(len(p.t_s) for p in series) == len(rows)
    for p in series:
        mine = [r for r in rows if r["probe"] == p.name]
        assert [int(r["frame_id"]) for r in mine] == list(p.frame_id)
        np.testing.assert_allclose(p.t_s, [float(r["t_s"]) for r in mine], atol=5e-7 + 1e-9, rtol=0)  # printed to 6 decimals
        for column in ("u_px", "v_px", "shift_px", "temperature_c", "sigma_u_px", "sigma_random_c"):
            printed = np.array([float(r[column]) if r[column] != "" else np.nan for r in mine])
            np.testing.assert_allclose(getattr(p, column), printed, rtol=1e-6, atol=1e-6, err_msg=column)
        np.testing.assert_array_equal(p.valid, [r["valid"] == "1" for r in mine])


def test_fits_and_agreements_are_the_stored_json(demo_run):
    run = bosfuse.Run(demo_run)
    db = sqlite3.connect(f"file:{demo_run / 'run.sqlite'}?mode=ro", uri=True)
    fits = db.execute("SELECT subject_kind, subject_id, ok, json FROM fits ORDER BY id").fetchall()
    agreements = db.execute("SELECT channel_id, probe_id, json FROM agreements ORDER BY id").fetchall()
    db.close()
    ours = run.fits()
    assert len(ours) == len(fits) and fits
    names = {"channel": {c.id: c.name for c in run.channels}, "probe": {p.id: p.name for p in run.probe_series()}}
    for mine, (kind, subject_id, ok, text) in zip(ours, fits):
        stored = json.loads(text)
        assert mine["subject"] == kind and mine["subject_id"] == subject_id and mine["ok"] == bool(ok)
        assert mine["name"] == names[kind][subject_id]
        for key in stored:
            if key != "ok":
                assert mine[key] == stored[key], key
        assert "parameters" in mine and "tau_s" in mine["parameters"]
    mine = run.agreements()
    assert len(mine) == len(agreements)
    for a, (channel_id, probe_id, text) in zip(mine, agreements):
        assert a["channel_id"] == channel_id and a["probe_id"] == probe_id
        assert {k: a[k] for k in json.loads(text)} == json.loads(text)
