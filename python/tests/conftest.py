"""Shared fixtures: where the build's executable and the sources are."""
import os
import pathlib
import subprocess

import pytest

BINARY_DIR = pathlib.Path(os.environ.get("BOSFUSE_BINARY_DIR", pathlib.Path(__file__).parents[2] / "build"))
SOURCE_DIR = pathlib.Path(os.environ.get("BOSFUSE_SOURCE_DIR", pathlib.Path(__file__).parents[2]))


DEMO_SPEED = 20


def run_cli(*args, timeout=120):
    """Runs the built `bosfuse` executable; returns its standard output (text)."""
    result = subprocess.run([str(BINARY_DIR / "bosfuse"), *map(str, args)], capture_output=True, text=True,
                            timeout=timeout)
    if result.returncode != 0:
        raise AssertionError(f"bosfuse {' '.join(map(str, args))} failed ({result.returncode}): {result.stderr}")
    return result.stdout


@pytest.fixture
def cli():
    return run_cli


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """A short demo run, recorded and processed (full fields) by `bosfuse demo`: 40 s of
    experiment at 20x, so that a loaded machine still records its frames every 10 s."""
    out = tmp_path_factory.mktemp("demo")
    run_cli("demo", "-o", out, "--experiment-time", "40s", "--speed", str(DEMO_SPEED), "--frame-interval", "10s",
            "--seed", "5", timeout=180)
    runs = [p for p in out.iterdir() if (p / "run.sqlite").exists()]
    assert len(runs) == 1
    return runs[0]
