"""The bundled sample log (``datasets/examples/sample_log.csv.gz``) in the form of a car's
log, from a dataset of acid's own plant: ``;``-separated, decimal comma, a Latin-1 header
with degree signs, km/h, kg/h, kW and W, gzip'd. Made once with

    acid excite --duration 1500 --cycle udds --t-amb 35 --seed 3 --out s.h5
    python tests/_sample_log.py s.h5 datasets/examples/sample_log.csv.gz

and imported with ``datasets/examples/sample_log_map.toml``; ``tests/test_examples.py``
checks that the import gives back the dataset's values.
"""

from __future__ import annotations

import gzip
import sys
from pathlib import Path

#: acid channel -> (column of the car log, unit in the log, decimals written)
COLUMNS = {
    "v_veh": ("Velocity [km/h]", "km/h", 2),
    "T_cab": ("Cabin Temperature [°C]", "degC", 2),
    "T_evap": ("Evaporator Temperature [°C]", "degC", 2),
    "T_ain": ("Vent Air Temperature [°C]", "degC", 2),
    "T_evap_set": ("Evaporator Setpoint [°C]", "degC", 2),
    "W_bl": ("Blower Flow [kg/h]", "kg/h", 1),
    "T_int": ("Interior Temperature [°C]", "degC", 2),
    "T_shell": ("Shell Temperature [°C]", "degC", 2),
    "T_amb": ("Ambient Temperature [°C]", "degC", 1),
    "P_comp": ("AC Power [kW]", "kW", 3),
    "P_bl": ("Blower Power [W]", "W", 0),
}
TIME = "Time [s]"


def car_log_bytes(ds) -> bytes:
    """The dataset ``ds`` as the gzip'd bytes of a car log (columns ``COLUMNS``)."""
    from acid.units import convert

    cols = [(TIME, ds.time - ds.time[0], 1)]
    for name, (col, unit, digits) in COLUMNS.items():
        cols.append((col, convert(ds[name], ds.units[name], unit), digits))
    lines = [";".join(c for c, _, _ in cols)]
    for i in range(len(ds)):
        lines.append(";".join(f"{v[i]:.{d}f}".replace(".", ",") for _, v, d in cols))
    text = "\r\n".join(lines) + "\r\n"
    return gzip.compress(text.encode("latin-1"), mtime=0)


if __name__ == "__main__":
    from acid.data import Dataset

    src, dest = sys.argv[1:3]
    Path(dest).write_bytes(car_log_bytes(Dataset.from_hdf5(src)))
    print(f"wrote {dest}")
