"""The soak-and-pull-down record design (``acid excite --design pulldown``)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.data import Dataset
from acid.errors import ConfigError
from acid.excite import ExcitationSpec, excite, segments, spec_for_model
from acid.plant import make_plant
from acid.units import C2K

runner = CliRunner()

#: four 3-min segments of the econ preset, half from a cold soak: ~1 s on the hifi plant
SPEC = spec_for_model("econ", design="pulldown", duration=720.0, segment_duration=180.0,
                      full_power_dwell=(30.0, 90.0), soak_bounds=(45.0, 55.0),
                      cold_fraction=0.5, seed=4)


@pytest.fixture(scope="module")
def record() -> Dataset:
    return excite(make_plant("hifi"), SPEC)


def test_segments_are_separate_experiments_from_their_soaks(record):
    ds, info = record, record.metadata["segments"]
    bounds = ds.segments()
    assert len(bounds) == len(info) == 4
    kinds = {s["kind"] for s in info}
    assert kinds == {"hot", "cold"}           # both soaks occur with this seed
    for (a, b), s in zip(bounds, info, strict=True):
        assert b - a == 36
        soak = s["soak_degC"]
        if s["kind"] == "hot":
            assert 45.0 <= soak <= 55.0
        else:                                  # a cold soak: the segment's ambient
            assert soak == pytest.approx(ds["T_amb"][a], abs=1e-9)
        for name in ("T_cab", "T_int", "T_shell", "T_evap", "T_cw", "T_int_slow"):
            assert ds[name][a] == pytest.approx(soak, abs=1e-9), name
        # the full-power hold at the segment's start
        h = int(round(s["full_power_s"] / SPEC.Ts))
        assert 6 <= h <= 18
        assert np.all(ds["W_bl"][a:a + h] == SPEC.W_bl_bounds[1])
        assert np.allclose(ds["T_evap_set"][a:a + h], SPEC.T_evap_set_bounds[0])
        assert ds["T_cab"][b - 1] < soak - 3.0     # it pulled down
    # a segment's first sample is not the previous segment's continuation
    assert np.unique(ds.experiment).tolist() == [0, 1, 2, 3]


def test_reruns_are_bit_identical_and_seeds_differ(record):
    again = excite(make_plant("hifi"), SPEC)
    for name, values in record.channels.items():
        assert np.array_equal(values, again[name], equal_nan=True), name
    assert again.metadata["segments"] == record.metadata["segments"]
    other = segments(SPEC.replace(seed=5))
    assert [s.soak_K for s in other] != [s.soak_K for s in segments(SPEC)]
    # segment i does not depend on how many segments follow it
    longer = segments(SPEC.replace(duration=1080.0))
    assert [s.spec.seed for s in longer[:4]] == [s.spec.seed for s in segments(SPEC)]


@pytest.mark.parametrize("kw, word", [
    ({"design": "soak"}, "--design"),
    ({"design": "pulldown", "soak_bounds": (50.0, 40.0)}, "soak_bounds"),
    ({"design": "pulldown", "segment_duration": 9000.0}, "--segment-duration"),
    ({"design": "pulldown", "cold_fraction": 1.5}, "--cold-fraction"),
    ({"design": "pulldown", "full_power_dwell": (-1.0, 30.0)}, "full-power"),
])
def test_spec_refuses_bad_designs(kw, word):
    with pytest.raises(ConfigError, match=word):
        ExcitationSpec(duration=3600.0, **kw)


def test_random_design_unchanged():
    spec = ExcitationSpec(duration=300.0, seed=2)
    assert spec.design == "random"
    with pytest.raises(ConfigError, match="not 'pulldown'"):
        segments(spec)


def test_cli_design_pulldown(tmp_path):
    out, summary = tmp_path / "pd.h5", tmp_path / "s.json"
    args = ["excite", "--plant", "hifi", "--model", "econ", "--design", "pulldown",
            "--duration", "360", "--segment-duration", "180", "--soak-range", "40", "50",
            "--seed", "7", "--out", str(out), "--json", str(summary)]
    result = runner.invoke(app(), args)
    assert result.exit_code == 0, result.output
    assert "2 pull-downs" in result.output
    ds = Dataset.from_hdf5(out)
    assert len(ds.segments()) == 2
    segs = json.loads(summary.read_text())["segments"]
    assert [s["soak_degC"] for s in segs] == [s["soak_degC"] for s in ds.metadata["segments"]]
    assert all(C2K(s["soak_degC"]) <= C2K(50.0) + 1e-9 for s in segs if s["kind"] == "hot")
    bad = runner.invoke(app(), ["excite", "--soak-range", "40", "50", "--out",
                                str(tmp_path / "x.h5")])
    assert_one_line_error(bad, "--design pulldown")


def app():
    from acid_cli.main import app as the_app

    return the_app
