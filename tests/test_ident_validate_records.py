"""A two-record per-experiment fit (``acid fit A --add-record B``) validated record by record:
each record with its own per-experiment values, only its held-out part scored (an in-sample
request said so), the yardsticks fitted on the estimation part of the fit's records only."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_ident_validate import _cabin3_record
from typer.testing import CliRunner

from acid.models import load
from acid_cli.main import app

runner = CliRunner()
N = 240                    # samples per record; the fit's estimation part is the first half


@pytest.fixture(scope="module")
def two_record_fit(tmp_path_factory):
    """Two records whose solar load Q_sol (per experiment) differs by 2 kW, fitted together
    by output error on the first half of each: (record paths, parameter file)."""
    m, folder = load("cabin3"), tmp_path_factory.mktemp("records")
    rng = np.random.default_rng(7)
    recs = []
    for i, q in enumerate((0.0, 2000.0)):
        p = m.values.copy()
        p[m.parameter_names.index("Q_sol")] = q
        recs.append(_cabin3_record(p, rng, n=N).to_hdf5(folder / f"r{i}.h5"))
    params = folder / "p.json"
    fit = runner.invoke(app, ["fit", str(recs[0]), "--model", "cabin3", "--add-record",
                              str(recs[1]), "--estimation-fraction", "0.5", "--out",
                              str(params), "--method", "oe"])
    assert fit.exit_code == 0, fit.output
    return recs, params


def _validate(record, params, tmp_path, capsys, held_out_fraction=None):
    """``acid validate RECORD --model cabin3 --params P --json`` as the command runs it,
    without drawing its figures."""
    from acid_cli._declared import validate_declared

    out = tmp_path / "v.json"
    capsys.readouterr()
    validate_declared(record, "cabin3", str(params), out, starts=4, horizon=20, warmup=100.0,
                      placement="even", seed=0, held_out_fraction=held_out_fraction,
                      figures=None)
    cap = capsys.readouterr()
    return " ".join((cap.out + cap.err).split()), json.loads(out.read_text())


@pytest.mark.parametrize("k", [0, 1])
def test_each_record_is_validated_with_its_own_values_on_its_held_out_part(
        two_record_fit, tmp_path, capsys, k):
    recs, params = two_record_fit
    text, d = _validate(recs[k], params, tmp_path, capsys)
    assert "their mean is used" not in text
    assert f"this record's own values (record {k + 1} of the fit)" in text
    assert d["channels"]["T_cab"]["max_abs"] < 0.05       # the mean (1000 W) is far off
    # only the part after the fit's estimation half is scored
    assert d["held_out_fraction_source"] == "params provenance"
    lo, hi = d["settings"]["sample_range"]
    first = hi - N                                        # DATA's first sample
    assert lo == first + N // 2 and min(d["starts"]) >= lo
    assert d["in_sample_warning"] is None


def test_the_yardsticks_are_fitted_on_the_estimation_part_only(two_record_fit, tmp_path,
                                                             capsys):
    recs, params = two_record_fit
    # each record: the yardsticks fitted on the first half of both records (what the
    # parameters were fitted on, placed before DATA), never on a held-out half
    for k in (1, 0):
        text, d = _validate(recs[k], params, tmp_path, capsys)
        assert d["settings"]["yardsticks_fitted_on"] == [0, N]
        assert "the first 50 % of each" in text and "(the estimation part)" in text
        lo, hi = d["settings"]["sample_range"]
        assert (lo, hi) == (N + N // 2, 2 * N)        # DATA's held-out half, after them


def test_an_in_sample_request_is_marked(two_record_fit, tmp_path, capsys):
    recs, params = two_record_fit
    text, d = _validate(recs[1], params, tmp_path, capsys, held_out_fraction=0.8)
    assert "partly in-sample" in text and "partly in-sample" in d["in_sample_warning"]
