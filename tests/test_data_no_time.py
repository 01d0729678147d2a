"""A log without a time column imports when the map gives Ts (rows one Ts apart)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import ChannelMap, from_csv
from acid.errors import DataError


def test_a_map_with_ts_needs_no_time_column(tmp_path):
    p = tmp_path / "log.csv"
    p.write_text("T\n" + "\n".join(f"{20 + 0.01 * k:.2f}" for k in range(50)) + "\n")
    cmap = ChannelMap.from_dict({"Ts": 5.0, "channels": {
        "T_cab": {"column": "T", "unit": "degC"}}})
    ds = from_csv(p, cmap)
    np.testing.assert_allclose(ds.time, np.arange(50) * 5.0)
    assert ds.Ts == 5.0 and ds.get("T_cab", "degC")[3] == pytest.approx(20.03)
    with pytest.raises(DataError, match=r"needs 'time' \(or Ts"):
        ChannelMap.from_dict({"channels": {"T_cab": {"column": "T", "unit": "degC"}}})
