"""The module's exception hierarchy."""
import bosfuse


def test_every_error_derives_from_bosfuse_error():
    for name in ("ConfigError", "StorageError", "DeviceError", "MemoryError", "NoStoredFields"):
        assert issubclass(getattr(bosfuse, name), bosfuse.Error), name
    assert issubclass(bosfuse.MemoryError, MemoryError)
