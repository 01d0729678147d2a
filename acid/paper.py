"""The paper's numbers: written here and nowhere else in acid. A data module: it imports
nothing of acid, so the models, the plant and the controllers read the paper's values without
reaching the claims or the studies that judge them.

H. Wang, I. Kolmanovsky, M. R. Amini and J. Sun, "Model Predictive Climate Control of
Connected and Automated Vehicles for Improved Energy Efficiency", ACC 2018. Everything else
reads them from here: the parameter preset (:func:`acid.models.params.paper`), the plant's
blower curve, the speed sweep's Table I, the CAV scenario's window, and the claims registry
(:mod:`acid.claims.registry`) that compares acid's measurements with them
(``tests/test_claims.py`` greps the tree for them).
"""

from __future__ import annotations

from dataclasses import dataclass

PAPER_CITATION = ("H. Wang, I. Kolmanovsky, M. R. Amini and J. Sun, Model Predictive Climate "
                  "Control of Connected and Automated Vehicles for Improved Energy Efficiency, "
                  "ACC 2018")


# =============================================================================
# The paper's numbers (written here and nowhere else)
# =============================================================================
@dataclass(frozen=True)
class PaperTableI:
    """Table I: A/C energy of the nominal controller over ``duration_s`` at constant speeds.

    ``energy_MJ_per_km`` is None at standstill ("NA" in the paper).
    """

    speeds_mps: tuple[float, ...] = (0.0, 5.0, 10.0, 15.0, 20.0, 25.0)
    energy_MJ: tuple[float, ...] = (1.33, 1.23, 1.17, 1.13, 1.10, 1.07)
    energy_MJ_per_km: tuple[float | None, ...] = (None, 0.410, 0.195, 0.126, 0.092, 0.071)
    duration_s: float = 600.0
    #: section II-A: "the efficiency ... increases by approximately 30 %" from 0 to 25 m/s
    efficiency_gain_pct: float = 30.0

    def energy_at(self, speed_mps: float) -> float | None:
        """Table I energy (MJ) at ``speed_mps``, None if the paper has no such speed."""
        for v, e in zip(self.speeds_mps, self.energy_MJ, strict=True):
            if abs(v - float(speed_mps)) < 1e-9:
                return e
        return None


@dataclass(frozen=True)
class PaperModel:
    """Identified parameters (section II-B-2, eq. 5; kelvin convention, Ts = 5 s)."""

    gamma: tuple[float, ...] = (0.2451, 0.0867, 1.2999, 1.0047, -0.5176, 0.4553, 34.9579)
    tau: tuple[float, ...] = (-0.1842, -1.3226, 154.4995)
    beta: tuple[float, ...] = (24156.0, -1974.2, 49.318)


@dataclass(frozen=True)
class PaperTableII:
    """Table II (NMPC settings and constants) and the sample time of section III-A."""

    N: int = 6
    eta_cop: float = 3.5
    c_p: float = 1008.0
    T_amb_degC: float = 30.0
    T_evap_max_degC: float = 12.0
    W_bl_max: float = 0.15
    T_evap_set_max_degC: float = 10.0
    T_cab_min_degC: float = 20.0
    T_evap_min_degC: float = 0.0
    W_bl_min: float = 0.05
    T_evap_set_min_degC: float = 3.0
    slack_penalty: float = 1e5
    Ts: float = 5.0


@dataclass(frozen=True)
class PaperStudies:
    """Settings and results of the validation, the NMPC runs and the CAV case."""

    validation_starts: int = 60
    validation_horizon: int = 300
    #: "within a couple of degrees for most of the time"
    validation_error_K: float = 2.0
    closed_loop_duration_s: float = 125.0
    #: "average time ... less than one eighth of the sampling period"
    computation_fraction_of_Ts: float = 1.0 / 8.0
    cav_window_s: tuple[float, float] = (10.0, 85.0)
    cav_shutoff_s: tuple[float, float] = (60.0, 80.0)
    cav_case1_MJ: float = 0.113
    cav_case2_MJ: float = 0.124
    cav_saving_pct: float = 9.0


TABLE_I = PaperTableI()
MODEL = PaperModel()
TABLE_II = PaperTableII()
STUDIES = PaperStudies()
