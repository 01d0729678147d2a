"""The top-level Python API (``import acid``): lazy, complete, unit-aware, and the README tour."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import acid
from acid.errors import ConfigError

README = Path(__file__).parents[1] / "README.md"


def test_import_acid_is_light():
    code = ("import sys, acid; heavy = [m for m in ('CoolProp', 'casadi', 'pandas', 'scipy', "
            "'matplotlib', 'cvxpy', 'h5py') if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_every_public_name_resolves():
    for name in acid.__all__:
        assert getattr(acid, name) is not None, name
    assert acid.load_dataset.__qualname__ == "Dataset.from_hdf5"
    assert "FmuPlant" in dir(acid)
    with pytest.raises(AttributeError, match="no attribute 'fitt'"):
        acid.fitt  # noqa: B018


def test_temperatures_are_unit_aware_and_never_guessed():
    t = acid.degC(35)
    assert float(t) == pytest.approx(308.15) and t.degC == pytest.approx(35.0)
    assert acid.kelvin(308.15).degC == pytest.approx(35.0)
    plant = acid.make_plant("hifi", T_amb=acid.degC(35))
    assert plant.cfg.T_amb == pytest.approx(308.15)
    spec = acid.ExcitationSpec(T_evap_set_bounds=(acid.degC(3), acid.degC(10)))
    assert spec.T_evap_set_bounds == pytest.approx(acid.ExcitationSpec().T_evap_set_bounds)
    with pytest.raises(ConfigError, match="not plausible in kelvin"):
        acid.make_plant("hifi", T_amb=35)


def _tour() -> str:
    text = README.read_text()
    section = text[text.index("## Python API"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_python_tour_runs_as_written(tmp_path):
    code = _tour()
    assert len([ln for ln in code.splitlines() if ln.strip()]) <= 12
    env = dict(os.environ, MPLBACKEND="Agg")
    res = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert "fit-oe" in res.stdout and "99 % band" in res.stdout
    assert (tmp_path / "resid.png").stat().st_size > 10_000
