"""bosfuse.quality, bosfuse.background and bosfuse.read_image against the
CLI's `quality --json -` and `background` on the same input."""
import json

import numpy as np
import pytest

import bosfuse
from conftest import run_cli
from images import write_pgm

PATTERN = dict(width=240, height=180, dot_px=2.5, coverage=0.45, grey_levels=(0, 60, 120), seed=7)
PATTERN_ARGS = ["--width", 240, "--height", 180, "--dot-px", 2.5, "--coverage", 0.45, "--grey-levels", "0,60,120",
                "--seed", 7]


def test_background_equals_the_cli_pattern(tmp_path):
    run_cli("background", "-o", tmp_path / "cli.png", *PATTERN_ARGS)
    cli = bosfuse.read_image(tmp_path / "cli.png")
    ours = bosfuse.background(**PATTERN, out=tmp_path / "ours.png")
    assert ours.dtype == np.uint8 and ours.shape == (180, 240)
    np.testing.assert_array_equal(ours, cli)
    np.testing.assert_array_equal(bosfuse.read_image(tmp_path / "ours.png"), cli)
    assert set(np.unique(ours)) >= {0, 255}
    assert not np.array_equal(bosfuse.background(**{**PATTERN, "seed": 8}), ours)


def test_background_rejects_what_the_cli_rejects():
    with pytest.raises(ValueError, match="coverage"):
        bosfuse.background(coverage=1.5)


def captured(pattern, seed=3):
    """The pattern as a camera sees it: dimmer, less contrast, noisy."""
    rng = np.random.default_rng(seed)
    image = 30 + 0.6 * pattern.astype(float) + rng.normal(0, 6, pattern.shape)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("window", [8, 11])
def test_quality_equals_the_cli_json(tmp_path, window):
    pattern = bosfuse.background(**PATTERN)
    image = captured(pattern)
    write_pgm(tmp_path / "image.pgm", image)
    write_pgm(tmp_path / "pattern.pgm", pattern)
    stdout = run_cli("quality", tmp_path / "image.pgm", "--reference", tmp_path / "pattern.pgm", "--json", "-",
                     "--window", window)
    cli = json.loads(stdout)
    ours = bosfuse.quality(image, pattern, window=window)
    for key, value in cli.items():
        if key in ("image", "reference"):
            continue
        if isinstance(value, float):
            assert ours[key] == pytest.approx(value, rel=1e-12, abs=1e-15), key
        else:
            assert ours[key] == value, key
    assert ours["verdict"] in ("good", "usable") and ours["reason"].startswith(ours["verdict"])
    assert ours["local_q_mod"].shape == (180 - window + 1, 240 - window + 1)
    assert np.nanmean(ours["local_q_mod"]) == pytest.approx(cli["mean_local_q_mod"], rel=1e-9)
    text = run_cli("quality", tmp_path / "image.pgm", "--reference", tmp_path / "pattern.pgm", "--window", window)
    assert f"verdict: {ours['reason']}" in text
    by_path = bosfuse.quality(tmp_path / "image.pgm", str(tmp_path / "pattern.pgm"), window=window)
    assert by_path["q_mod"] == ours["q_mod"]


def test_quality_of_unrelated_images_is_not_the_same_scene():
    pattern = bosfuse.background(**PATTERN)
    other = bosfuse.background(**{**PATTERN, "seed": 99})
    assert bosfuse.quality(other, pattern)["verdict"] == "not the same scene"


def test_read_image_keeps_the_depth(tmp_path):
    with pytest.raises(bosfuse.Error, match="no such file"):
        bosfuse.read_image(tmp_path / "missing.png")
