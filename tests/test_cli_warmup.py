"""``acid validate --warmup`` is seconds, like cav-study's and heating-control's (issue 23):
converted with the dataset's Ts, rounded up to whole samples, said once."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from acid.excite import ExcitationSpec, excite
from acid.plant import make_plant
from acid_cli.main import app
from acid_cli.validate import warmup_samples


@pytest.mark.parametrize(("seconds", "Ts", "samples", "said"),
                         [(300.0, 5.0, 60, False), (0.0, 5.0, 0, False),
                          (302.0, 5.0, 61, True), (0.1, 10.0, 1, True), (0.3, 0.1, 3, False)])
def test_seconds_become_whole_samples_rounded_up(capsys, seconds, Ts, samples, said):
    assert warmup_samples(seconds, Ts) == samples
    out = capsys.readouterr().out
    assert ("not a whole number of samples" in out) is said


def test_validate_reads_warmup_in_seconds_and_says_the_rounding_once(tmp_path):
    data = tmp_path / "d.h5"
    excite(make_plant("hifi"), ExcitationSpec(duration=1200.0, seed=4)).to_hdf5(data)
    base = ["validate", str(data), "--model", "cabin3", "--starts", "3", "--horizon", "20",
            "--no-yardsticks", "--out", str(tmp_path / "figs"), "--no-figures"]
    res = CliRunner().invoke(app, [*base, "--warmup", "302", "--json", str(tmp_path / "a.json")])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert text.count("--warmup 302 s is not a whole number of samples of 5 s: 61 samples "
                      "(305 s) are used") == 1
    assert json.loads((tmp_path / "a.json").read_text())["warmup"] == 61
    res = CliRunner().invoke(app, [*base, "--json", str(tmp_path / "b.json")])
    assert res.exit_code == 0, res.output
    assert "whole number" not in res.output                    # the default is 60 samples
    assert json.loads((tmp_path / "b.json").read_text())["warmup"] == 60
