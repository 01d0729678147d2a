"""Refrigerant property tables: the on-disk cache returns exactly what CoolProp builds."""

from __future__ import annotations

import numpy as np

from acid.plant import refrigerant


def test_disk_cache_round_trip_is_exact(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_CACHE_DIR", str(tmp_path))
    refrigerant.table.cache_clear()
    try:
        built = refrigerant.table("R134a", 5.0, 5.0)
        files = list(tmp_path.glob("refrigerant-R134a-*.npz"))
        assert len(files) == 1
        refrigerant.table.cache_clear()
        loaded = refrigerant.table("R134a", 5.0, 5.0)
        for name in refrigerant._ARRAYS:
            np.testing.assert_array_equal(getattr(loaded, name), getattr(built, name))
        assert refrigerant._cache_file("R134a", 5.0, 6.0) != files[0]  # keyed by subcooling
    finally:
        refrigerant.table.cache_clear()


def test_corrupt_cache_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_CACHE_DIR", str(tmp_path))
    refrigerant.table.cache_clear()
    try:
        path = refrigerant._cache_file("R134a", 5.0, 5.0)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"not a numpy file")
        tab = refrigerant.table("R134a", 5.0, 5.0)
        assert np.all(np.diff(tab.p_sat) > 0)  # saturation pressure rises with temperature
    finally:
        refrigerant.table.cache_clear()
