"""The line-visibility audit of figures (``acid.report.audit``) and the figures it guards."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from acid.report.audit import audit_figure
from acid.report.figures import read_figure_index, save_report_figure, write_figure_index
from acid.report.mpc import closed_loop_figure
from acid.studies.mpc_check.scenarios import ClosedLoopRun, ScenarioResult
from acid.units import C2K


def _hidden(fig) -> set[str]:
    return {h.label for h in audit_figure(fig, dpi=120).hidden}


def test_a_line_drawn_under_an_identical_one_is_hidden_and_styles_fix_it():
    t = np.linspace(0.0, 10.0, 200)
    y = np.sin(t)
    fig = Figure(figsize=(6, 4))
    ax = fig.subplots()
    ax.plot(t, y, color="tab:blue", label="A")
    ax.plot(t, y, color="tab:green", label="C over A")
    ax.plot(t, y + 5, color="k", label="out of view")
    ax.plot([], [], color="grey", label="legend proxy (no data)")
    ax.set_ylim(-2, 2)
    ax.legend()
    assert _hidden(fig) == {"A", "out of view"}

    fig = Figure(figsize=(6, 4))
    ax = fig.subplots()
    ax.plot(t, y, color="tab:blue", lw=2.6, label="A wide")
    ax.plot(t, y, color="tab:green", lw=1.2, ls="--", label="C thin, dashed")
    assert _hidden(fig) == set()


def test_the_audit_leaves_the_figure_as_it_was():
    fig = Figure(figsize=(4, 3), dpi=77)
    line, = fig.subplots().plot([0, 1], [0, 1], label="x")
    audit_figure(fig)
    assert fig.dpi == 77 and line.get_antialiased()


def _run(label, W_bl) -> ClosedLoopRun:
    n = W_bl.size
    T = np.full(n + 1, C2K(25.0))
    return ClosedLoopRun(
        label=label, Ts=5.0, time=np.arange(n + 1) * 5.0, T_cab=T, T_evap=T - 20.0,
        T_int=T, T_shell=T, T_cab_max=T + 1.0, T_cab_min=T - 5.0, T_evap_min=C2K(0.0),
        T_evap_max=C2K(12.0), W_bl=W_bl, T_evap_set=np.full(n, C2K(3.0)), v_veh=np.zeros(n),
        T_ain=np.full(n, C2K(10.0)), P_comp=np.full(n, 500.0), P_bl=np.full(n, 100.0),
        P_fan=np.zeros(n), compressor_on=np.ones(n, bool), step_ms=np.ones(n),
        fallback=np.zeros(n, bool), iterations=np.ones(n, int),
        predicted_T_cab=np.zeros((n, 7)))


def test_closed_loop_figure_keeps_coinciding_runs_visible(tmp_path):
    """Two runs with identical trajectories (as at an input bound): both stay visible."""
    W = np.full(25, 0.15)
    res = ScenarioResult(name="plant", title="t", runs=(_run("hot start", W),
                                                        _run("cool start", W.copy())))
    fig = closed_loop_figure(res)
    rec = save_report_figure(fig, tmp_path, "fig8", "caption")
    assert rec.hidden == () and rec.labelled_lines >= 12
    write_figure_index(tmp_path, [rec])
    assert read_figure_index(tmp_path) == [rec] and (tmp_path / "fig8.png").is_file()
