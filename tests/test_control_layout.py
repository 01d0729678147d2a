"""Declared NLP layouts: indices come from the declaration, shifts move stages."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from acid.control.layout import BlockVector
from acid.control.nmpc import NMPC
from acid.control.ocp import stage_shift
from acid.models.params import paper


def _ocp_vector(N=3):
    w = BlockVector("w")
    for i in range(N):
        w.sym("x", i, 2)
        w.sym("u", i, 2)
    w.sym("x", N, 2)
    return w


def test_indices_follow_the_order_of_declaration():
    w = _ocp_vector(3)
    assert w.size == 14
    np.testing.assert_array_equal(w.index("x"), [[0, 1], [4, 5], [8, 9], [12, 13]])
    np.testing.assert_array_equal(w.index("u", 1), [3, 7, 11])
    np.testing.assert_array_equal(w.at("u", 2), [10, 11])
    assert w.blocks == ("x", "u") and w.stages("u") == [0, 1, 2]
    v = w.vertcat()
    assert v.shape == (14, 1) and str(v[w.at("u", 1)[0]]) == "u_1_0"


def test_a_block_cannot_be_declared_twice_or_change_size():
    w = BlockVector("w")
    w.sym("x", 0, 2)
    with pytest.raises(ValueError, match="twice"):
        w.sym("x", 0, 2)
    with pytest.raises(ValueError, match="changes size"):
        w.add("x", 1, ca.SX.sym("z", 3))


def test_stage_shift_moves_each_block_one_stage_and_keeps_the_last():
    w = _ocp_vector(3)
    values = np.arange(w.size, dtype=float)
    shifted = values[stage_shift(w)]
    np.testing.assert_array_equal(shifted[w.index("x")[:-1].ravel()],
                                  values[w.index("x")[1:].ravel()])
    np.testing.assert_array_equal(shifted[w.at("u", 2)], values[w.at("u", 2)])  # repeated
    np.testing.assert_array_equal(shifted[w.at("x", 3)], values[w.at("x", 3)])  # terminal


def test_stage_shift_holds_the_horizons_last_stages_in_place():
    w = _ocp_vector(5)   # x_0..x_5, u_0..u_4
    values = np.arange(w.size, dtype=float)
    shifted = values[stage_shift(w, hold=2)]
    x, u = w.index("x"), w.index("u")
    # x_0..x_2 take x_1..x_3; x_3, x_4, x_5 stay; u_0, u_1 take u_1, u_2; u_2..u_4 stay
    np.testing.assert_array_equal(shifted[x[:3].ravel()], values[x[1:4].ravel()])
    np.testing.assert_array_equal(shifted[x[3:].ravel()], values[x[3:].ravel()])
    np.testing.assert_array_equal(shifted[u[:2].ravel()], values[u[1:3].ravel()])
    np.testing.assert_array_equal(shifted[u[2:].ravel()], values[u[2:].ravel()])
    # holding everything is no shift; hold=0 is the plain shift
    np.testing.assert_array_equal(stage_shift(w, hold=9), np.arange(w.size))
    np.testing.assert_array_equal(stage_shift(w, hold=0), stage_shift(w))


def test_the_nmpc_holds_its_plans_end_arc_for_fewer_iterations_and_the_same_moves():
    """The paper's plans end in an arc tied to the horizon's end: a warm start that keeps it
    in place needs fewer SQP iterations (deterministic, CasADi's count) for the same moves."""
    from acid.control.nmpc import NMPCConfig
    from acid.studies.mpc_check.scenarios import run_model_scenario

    moves, iterations = {}, {}
    for hold in (0, 2):
        res = run_model_scenario(paper(), NMPCConfig(compiled=False, warm_start_hold=hold),
                                 duration_s=150.0)
        moves[hold] = np.concatenate([np.column_stack((r.W_bl, r.T_evap_set))
                                      for r in res.runs])
        iterations[hold] = sum(int(r.iterations.sum()) for r in res.runs)
    np.testing.assert_allclose(moves[2], moves[0], rtol=0, atol=1e-8)
    assert iterations[2] < 0.95 * iterations[0], iterations


@pytest.mark.parametrize("hold", [-1, 1.5, "2", True])
def test_a_warm_start_hold_that_is_no_stage_count_is_one_line(hold):
    from acid.control.nmpc import NMPCConfig
    from acid.errors import ConfigError

    with pytest.raises(ConfigError, match="warm_start_hold"):
        NMPCConfig(warm_start_hold=hold)


def test_the_nmpc_index_maps_come_from_its_layout():
    mpc = NMPC(paper())
    w, g = mpc._w, mpc._g
    N = mpc.N
    assert w.size == N * (2 + 2 + 4) + 2
    assert g.size == 2 + N * (2 + 4)
    np.testing.assert_array_equal(mpc._iT_cab, w.index("x", 0))
    assert set(g.blocks) == {"init", "dyn", "T_cab_hi", "T_cab_lo", "T_evap_hi", "T_evap_lo"}
