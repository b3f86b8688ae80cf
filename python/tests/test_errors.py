"""The module's exception hierarchy."""
import bosfuse


def test_every_error_derives_from_bosfuse_error():
    for name in ("ConfigError", "StorageError", "DeviceError", "MemoryError", "NoStoredFields"):
        assert issubclass(getattr(bosfuse, name), bosfuse.Error), name
    assert issubclass(bosfuse.MemoryError, MemoryError)


import numpy as np  # noqa: E402
import pytest  # noqa: E402

from images import pair  # noqa: E402


@pytest.fixture(scope="module")
def images():
    return pair(rows=64, cols=64)


def test_bad_arrays_are_value_errors(images):
    ref, meas = images
    cases = [
        (ref.astype(np.int32), "dtype int32"),
        (np.stack([ref, ref]), "2-D array"),
        (np.asfortranarray(ref), "not C-contiguous"),
        (ref[:, ::2], "not C-contiguous"),
        (np.zeros((0, 64), np.uint8), "empty"),
        ([[1, 2], [3, 4]], "NumPy array or a path"),
    ]
    for bad, words in cases:
        with pytest.raises(ValueError, match=words):
            bosfuse.evaluate(bad, meas)
    with pytest.raises(ValueError, match="differ in size"):
        bosfuse.evaluate(ref, meas[:32])


def test_bad_options(images):
    ref, meas = images
    with pytest.raises(TypeError, match="unknown option 'windw'"):
        bosfuse.evaluate(ref, meas, windw=16)
    with pytest.raises(ValueError, match="subpixel 'gauss9'"):
        bosfuse.evaluate(ref, meas, subpixel="gauss9")
    with pytest.raises(ValueError, match="window"):
        bosfuse.evaluate(ref, meas, window=3)
    with pytest.raises(ValueError, match="roi"):
        bosfuse.evaluate(ref, meas, roi=(0, 0, 10))
    with pytest.raises(ValueError, match="outside the 64x64 image"):
        bosfuse.evaluate(ref, meas, probes=[(70, 3)])


def test_unreadable_file_and_bad_settings_file(tmp_path, images):
    ref, meas = images
    with pytest.raises(bosfuse.Error, match="nothing.png"):
        bosfuse.evaluate(tmp_path / "nothing.png", meas)
    settings = tmp_path / "settings.toml"
    settings.write_text("[processing]\nwindow_px = 'big'\n")
    with pytest.raises(bosfuse.ConfigError, match="window_px"):
        bosfuse.evaluate(ref, meas, settings=settings)
