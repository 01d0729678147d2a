"""The econ model with a slow interior node (acid.models.econ2), its identification's
interior stage and the pull-down controller that carries the slow node."""

from __future__ import annotations

import casadi as ca
import numpy as np
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.ident.econ import interior_output_error, simulate_interior
from acid.models import econ, econ2


def test_slow_trace_is_the_exact_first_order_response_restarted_per_experiment():
    Ts, C, hA = 5.0, 90e3, 60.0
    T_int = np.r_[np.full(50, 300.0), np.full(50, 310.0)]
    exp = np.r_[np.zeros(50, int), np.ones(50, int)]
    tr = econ2.slow_trace(np.r_[313.0, np.full(49, 300.0), T_int[50:]], exp, C, hA, Ts)
    k = np.arange(1, 50)
    # soaked at 313 K, then a 300 K interior (held from sample 1 on, read at k - 1):
    # 300 + 13 exp(-(t - Ts) / tau), exact at the samples
    assert np.allclose(tr[1:50], 300.0 + 13.0 * np.exp(-(k - 1) * Ts * hA / C), atol=1e-9)
    assert tr[50] == 310.0 and np.allclose(tr[50:], 310.0)   # second record starts soaked


def test_econ2_without_coupling_is_econ_and_a_warm_slow_node_warms_the_cabin():
    p1 = econ.model.values.copy()
    x = [300.0, 302.0, 305.0, 285.0, 0.009]
    u, d = [0.1, 279.0], [10.0, 305.0]
    base = econ.interval(econ.parameters(p1), x, u, d, 60.0)
    th = np.r_[p1, 9e4, 1e-9]
    off = econ2.interval(econ2.parameters(th), [*x, 315.0], u, d, 60.0)
    assert abs(float(ca.evalf(off.x[0])) - float(ca.evalf(base.x[0]))) < 1e-6
    on = econ2.interval(econ2.parameters(np.r_[p1, 9e4, 60.0]), [*x, 315.0], u, d, 60.0)
    assert float(ca.evalf(on.x[1])) > float(ca.evalf(base.x[1])) + 0.01   # interior
    assert float(ca.evalf(on.x[0])) > float(ca.evalf(base.x[0]))          # cabin
    assert float(ca.evalf(on.x[5])) < 315.0                               # slow node cools


def test_interior_output_error_recovers_a_slow_node_from_soaked_pull_downs():
    rng = np.random.default_rng(3)
    Ts, n = 5.0, 720
    t = np.arange(n) * Ts
    truth = {"C_int": 35e3, "Q_int": 300.0, "C_is": 90e3, "hA_is": 60.0}
    cabins, ints, exps = [], [], []
    for j, soak in enumerate((318.0, 308.0, 313.0)):
        T_cab = 297.0 + (soak - 297.0) * np.exp(-t / 300.0)   # a pull-down from the soak
        X = simulate_interior([truth[k] for k in ("C_int", "Q_int", "C_is", "hA_is")],
                              T_cab, np.full(n, soak), np.zeros(n, int), Ts, 190.0)
        cabins.append(T_cab)
        ints.append(X[:, 0] + 0.01 * rng.standard_normal(n))
        exps.append(np.full(n, j))

    class Rec:
        experiment = np.concatenate(exps)
        Ts = 5.0

        def get(self, name, unit):
            return np.concatenate(cabins if name == "T_cab" else ints)

    m = econ2.model
    start = {"C_int": 60e3, "Q_int": 0.0, "C_is": 30e3, "hA_is": 20.0}
    bounds = {k: (m.parameter(k).min, m.parameter(k).max) for k in start}
    bounds["Q_int"] = (-1e4, 1e4)
    val, se, rep = interior_output_error(Rec(), 190.0, start, bounds, {})
    for k, v in truth.items():
        assert abs(val[k] - v) < 0.05 * abs(v), (k, val[k])
    assert rep["rms_T_int_K"] < 0.02 and not rep["on_bound"]


def test_the_controller_carries_the_slow_node_and_hands_its_heat_to_the_nmpc():
    from acid.studies.pulldown.slow import SlowInterior

    class MPC:   # records what the NMPC was given
        config = type("C", (), {"intervals": (5.0,) * 3})()
        log = None

        def __init__(self):
            self.dist = []

        def reset(self):
            pass

        def make_step(self, x, v, Ta, dist=None, **kw):
            self.dist.append(np.asarray(dist))
            return np.array([0.1, 276.0])

    class Preview:
        def __init__(self):
            self.mpc, self.comfort, self.setting = MPC(), True, 297.0
            self.sc = type("S", (), {"Ts": 5.0})()
            self.v, self.T_amb, self.log = np.zeros(20), np.full(20, 303.0), None

        def reset(self):
            pass

    class Fit:
        hA_is, C_is = 60.0, 90e3
        params = type("P", (), {"C_int": 35e3})()

    ctrl = SlowInterior(Preview(), Fit(), 5.0)
    ctrl.reset()
    T_int = np.r_[313.0, np.linspace(305.0, 300.0, 9)]
    for k, Ti in enumerate(T_int):
        ctrl.make_step({"T_cab": 300.0, "T_int": Ti, "T_shell": 310.0, "T_evap": 290.0,
                        "w_cab": 0.01}, k)
    trace = econ2.slow_trace(T_int, None, 90e3, 60.0, 5.0)
    got = np.array([d[1] for d in ctrl.mpc.dist]) * 35e3 / 60.0 + T_int
    assert np.allclose(got, trace, atol=1e-9)
    assert ctrl.mpc.dist[0][1] == 0.0 and ctrl.mpc.dist[-1][1] > 0.0   # soaked: no flow yet
    assert all(d[0] == 0.0 and d[2:].tolist() == [0.0, 0.0, 0.0] for d in ctrl.mpc.dist)


def test_cli_pulldown_refuses_an_unknown_econ_model():
    from acid_cli.main import app

    result = CliRunner().invoke(app, ["pulldown", "--econ-model", "econ3"])
    assert_one_line_error(result, "econ-model")


def test_a_lowered_target_is_charged_the_common_continuation():
    """The continuation after a pass is the plant's own loops at the default set-point for
    every run: a run with a lowered target is not charged 40 min of a colder cabin."""
    import dataclasses

    from acid.plant.hifi import HifiPlant, physical_state
    from acid.studies.cav_study import plant_state
    from acid.studies.compare import MATCH_SHIFT_K, RunSettings, tail_J
    from acid.studies.pulldown import cases

    base = RunSettings(max_passes=1)
    low = dataclasses.replace(base, T_set=base.T_set - MATCH_SHIFT_K)
    sc = cases.case("sc03", 30.0, 36.0, 850.0)
    run = cases.run_case(sc, "own", settings=low)
    plant = HifiPlant(sc.plant_config(), mode="nominal")   # the same pass, replayed
    plant.reset(sc.start())
    drive, E = sc.drive(), 0.0
    for k in range(drive.n):
        row = plant.step(0.0, 0.0, float(drive.v[k]), T_amb=float(drive.T_amb[k]),
                         T_cab_set=low.T_set)
        E += (float(row["P_comp"]) + float(row["P_bl"])) * drive.Ts
    assert abs(E - run.energy_J) < 1e-6 * E
    tail = tail_J(sc, physical_state(plant_state(plant)), "own", base)
    assert abs(run.charged_J - run.energy_J - tail) < 1e-6 * tail
