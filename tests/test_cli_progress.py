"""Progress that moves when the output is a log (issue 23): with stderr not a terminal
(``| tee``, CI, typer's CliRunner) long commands print plain progress lines, not a rich bar
that is swallowed."""

from __future__ import annotations

import re

from typer.testing import CliRunner

import acid_cli._common as common
from acid.pipeline import Stage
from acid_cli._common import ProgressLines, progress_bar, progress_is_plain
from acid_cli.main import app
from acid_cli.reproduce import _run_with_lines

LINE = re.compile(r"^(?P<what>.+): (?P<done>\d+)/(?P<total>\d+) \((?P<pct>\d+) %\), "
                  r"(?P<s>\d+) s(: (?P<label>.+))?$")


def _lines(text: str, prefix: str) -> list[re.Match]:
    return [m for line in text.splitlines() if line.startswith(prefix)
            and (m := LINE.match(line))]


def test_one_line_per_tenth_each_label_and_the_end(capsys):
    assert progress_is_plain()                         # pytest's stderr is not a terminal
    with progress_bar("sweep", 8) as update:
        for i in range(1, 9):
            update(i, label=f"scenario {i}" if i in (3, 5) else None)
            update(i)                                  # the same count again: no line
    with progress_bar("excite", 1440) as update:
        for i in range(1441):
            update(i)
    err = capsys.readouterr().err
    sweep = _lines(err, "sweep")
    assert [int(m["done"]) for m in sweep] == list(range(1, 9))  # 8 steps: each a tenth
    assert [m["label"] for m in sweep if m["label"]] == ["scenario 3", "scenario 5"]
    excite = _lines(err, "excite")
    assert [int(m["pct"]) for m in excite] == list(range(0, 101, 10))
    assert excite[-1]["done"] == excite[-1]["total"] == "1440"


def test_a_line_at_least_every_interval_while_the_count_moves(capsys, monkeypatch):
    clock = iter(range(0, 10_000, 40))                 # 40 s between updates
    monkeypatch.setattr(common.time, "monotonic", lambda: float(next(clock)))
    lines = ProgressLines("plan", 1000)
    for i in (1, 2, 3, 3):                             # under a tenth, but 40 s apart
        lines(i)
    got = _lines(capsys.readouterr().err, "plan")
    assert [int(m["done"]) for m in got] == [1, 2, 3]
    assert [int(m["s"]) for m in got] == [40, 80, 120]


def test_a_command_into_a_log_shows_its_progress(tmp_path):
    res = CliRunner().invoke(app, ["excite", "--duration", "600", "--out",
                                   str(tmp_path / "d.h5")])
    assert res.exit_code == 0, res.output
    got = _lines(res.output, "exciting hifi plant")
    assert got and got[-1]["done"] == got[-1]["total"] == "120" and len(got) <= 12


def _slow_stage(workdir, inputs, config, progress):
    for i in range(1, 5):
        progress(i, 4)
    return {"n": 4}


def test_reproduce_into_a_log_names_each_stage_as_it_starts_moves_and_ends(tmp_path, capsys):
    stages = [Stage("a", "first stage", _slow_stage, {"x": 1}),
              Stage("b", "second stage", _slow_stage, {"x": 2}, depends=("a",))]
    _run_with_lines(stages, tmp_path, 1, None, False, print)
    err = capsys.readouterr().err
    for title in ("first stage", "second stage"):
        assert re.search(rf"^stage {title}: queued, \d+ s$", err, re.M)
        moved = _lines(err, f"stage {title}")
        assert [int(m["done"]) for m in moved] == [1, 2, 3, 4]
        assert re.search(rf"^stage {title}: done in \d+\.\d s$", err, re.M)
    assert err.index("first stage: done") < err.index("second stage: queued")
    _run_with_lines(stages, tmp_path, 1, None, False, print)   # again: from the cache
    err = capsys.readouterr().err
    assert "stage first stage: cached" in err and "stage second stage: cached" in err


def test_a_study_of_several_cycles_moves_in_plant_steps_not_per_cycle(monkeypatch):
    """reproduce's longest stage (where the energy is: UDDS and SC03 in one process) reported
    only 1/2 and 2/2: a log was silent for a whole cycle. It counts plant steps over both."""
    from types import SimpleNamespace

    import acid.studies.cav_study as cs
    from acid.models.params import paper

    def study_cycle(params, econ, name, config, plant_factory, progress=None):
        for _ in range(3):
            progress(100)                              # one run of 100 plant steps
        return name

    monkeypatch.setattr(cs, "study_cycle", study_cycle)
    monkeypatch.setattr(cs, "estimated_steps", lambda config, n, Ts: 300)
    econ = SimpleNamespace(name="econ", provenance={}, power_map=SimpleNamespace(domain={}))
    seen = []
    cs.cav_study(paper(), ["udds", "sc03"], cs.StudyConfig(), econ=econ,
                 plant_factory=lambda: None, progress=lambda done, total: seen.append(
                     (done, total)))
    assert seen == [(100 * i, 600) for i in range(1, 7)] + [(600, 600)]


def test_a_bar_on_a_terminal_names_the_last_finished_step_literally(monkeypatch):
    import io

    from rich.console import Console

    term = Console(file=io.StringIO(), force_terminal=True, width=150, stderr=True)
    monkeypatch.setattr(common, "err_console", term)
    assert not progress_is_plain()
    with progress_bar("sweep [b]x[/b]", 3) as update:
        update(1, label="grid scenario #1 (params = 'p[red]x.json')")
        update(2)                                      # no label: the last one stays
    out = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", term.file.getvalue())
    last = out.strip().splitlines()[-1]
    assert "sweep [b]x[/b]" in last and "2/3" in last
    assert last.endswith("grid scenario #1 (params = 'p[red]x.json')")


def test_validate_into_a_log_names_each_step(model_dataset, tmp_path):
    """``acid validate``'s windows, residual tests and figures, one line each (before: none
    until the report); the report itself comes after them."""
    data = model_dataset.to_hdf5(tmp_path / "d.h5")
    res = CliRunner().invoke(app, ["validate", str(data), "--starts", "20", "--horizon", "120",
                                   "--no-yardsticks", "--out", str(tmp_path / "figs")])
    assert res.exit_code == 0, res.output
    got = _lines(res.output, "validate paper")
    assert [(int(m["done"]), int(m["total"])) for m in got] == [(i, 5) for i in range(1, 6)]
    assert [m["label"] for m in got] == [
        "20 starts placed", "20 windows of 120 steps simulated", "errors scored",
        "one-step residuals tested", "2 figures drawn"]
    assert res.output.index("2 figures drawn") < res.output.index("Open-loop prediction error")
