"""The periodic steady state of the comparison engine admits a period-2 orbit (two passes
that alternate): detected on the two-pass map, its figures are the two passes' mean."""

from __future__ import annotations

import dataclasses
import math

import pytest

from acid.control.pi_baselines import PlantPI
from acid.studies import compare as cmp
from acid.units import C2K

S = cmp.RunSettings(tol_K=0.05, tol_w=1e-4, tol_E=2e-3, max_passes=30)


def _sc() -> cmp.Scenario:
    return cmp.Scenario("stopgo", C2K(32.0), stopgo_s=160.0, soak_K=C2K(26.0))


class Alternating:
    """acid's sampled fixed-coil PI whose coil set-point alternates from pass to pass (every
    pass starts with ``reset``): the closed loop's pass map has a period-2 orbit."""

    def __init__(self, a: PlantPI, b: PlantPI):
        self.pis, self.i = (a, b), 1

    def reset(self):
        self.i = 1 - self.i
        self.pis[self.i].reset()

    def make_step(self, meas, k):
        return self.pis[self.i].make_step(meas, k)


@pytest.fixture(scope="module")
def warm() -> cmp.PeriodicRun:
    """The engine's common start: F's periodic state at 8 degC (period 1)."""
    return cmp.periodic_run(_sc(), "F", C2K(8.0), settings=S)


@pytest.fixture
def alternating(monkeypatch):
    """Family "Fs" with its coil set-point alternating between 6 and 10 degC, and the
    energies of every pass run."""
    real_controller, real_pass, energies = cmp._controller, cmp._pass, []

    def controller(family, knob, settings, cfg, drive, econ):
        nominal, pi, c = real_controller(family, knob, settings, cfg, drive, econ)
        other = PlantPI(cfg, drive.Ts, settings.T_set, C2K(10.0), pi.p_atm)
        return nominal, Alternating(pi, other), c

    def one_pass(plant, ctrl, drive, T_set):
        out = real_pass(plant, ctrl, drive, T_set)
        energies.append(out[0])
        return out

    monkeypatch.setattr(cmp, "_controller", controller)
    monkeypatch.setattr(cmp, "_pass", one_pass)
    return energies


def test_a_period_two_orbit_is_found_and_its_figure_is_the_two_passes_mean(warm, alternating):
    # (the interior's slow mode settles in some 10-30 passes)
    s2 = dataclasses.replace(S, max_passes=60)
    r = cmp.periodic_run(_sc(), "Fs", C2K(6.0), settings=s2, start=warm.end)
    assert r.period == 2 and r.converged and r.residual_K < S.tol_K
    assert r.passes == len(alternating) < s2.max_passes
    a, b = alternating[-2:]
    assert abs(a - b) / b > 10 * S.tol_E                  # the two passes differ
    assert r.energy_J == pytest.approx((a + b) / 2.0, rel=1e-15)
    # the period-1 rule alone never settles on it (the passes keep alternating)
    alternating.clear()
    one = cmp.periodic_run(_sc(), "Fs", C2K(6.0), start=warm.end,
                           settings=dataclasses.replace(s2, max_period=1))
    assert one.period == 1 and not one.converged and one.passes == s2.max_passes


def test_a_period_one_state_is_unchanged_by_the_period_two_test(warm):
    """Bit for bit: the figures of a run that settles on period 1 are those of the period-1
    rule alone (the last pass)."""
    alone = cmp.periodic_run(_sc(), "F", C2K(8.0), settings=dataclasses.replace(S, max_period=1))
    assert warm.period == alone.period == 1 and warm.converged and warm.passes >= 3
    a, b = dataclasses.asdict(warm), dataclasses.asdict(alone)
    assert [k for k in a if a[k] != b[k] and not (isinstance(a[k], float) and math.isnan(a[k])
                                                  and math.isnan(b[k]))] == []
