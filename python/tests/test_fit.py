"""bosfuse.fit_newton against `bosfuse fit --json`."""
import json

import numpy as np
import pytest

import bosfuse
from conftest import run_cli


def cooling(n=120, seed=3):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 600, n)
    temperature = 22 + 58 * np.exp(-t / 180) + rng.normal(0, 0.15, n)
    return t, temperature


def cli_fit(tmp_path, t, temperature, *args):
    path = tmp_path / "series.csv"
    with open(path, "w") as f:
        f.write("t_s,T\n")
        for a, b in zip(t, temperature):
            f.write(f"{a!r},{b!r}\n")
    document = json.loads(run_cli("fit", path, "--json", "-", *args))
    document.pop("input")
    return document


@pytest.mark.parametrize("options,args", [
    ({}, []),
    ({"ambient": 22.0, "sigma": 0.15}, ["--ambient", "fixed:22.0", "--sigma", "0.15"]),
    ({"ambient": "prior:21.5,0.5", "loss": "huber:0.3", "confidence": 0.9},
     ["--ambient", "prior:21.5,0.5", "--loss", "huber:0.3", "--confidence", "0.9"]),
])
def test_fit_equals_the_cli_json(tmp_path, options, args):
    t, temperature = cooling()
    ours = bosfuse.fit_newton(t, temperature, **options)
    assert ours == cli_fit(tmp_path, t, temperature, *args)
    assert ours["ok"] and abs(ours["parameters"]["tau_s"]["value"] - 180) < 10


def test_bad_fit_input():
    t, temperature = cooling()
    with pytest.raises(ValueError, match="differ in length"):
        bosfuse.fit_newton(t, temperature[:-1])
    with pytest.raises(ValueError, match="1-D"):
        bosfuse.fit_newton(np.stack([t, t]), np.stack([temperature, temperature]))
    with pytest.raises(bosfuse.Error, match="ambient 'warm'"):
        bosfuse.fit_newton(t, temperature, ambient="warm")
