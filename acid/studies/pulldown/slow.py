"""The pull-down study on the econ model with a slow interior node (:mod:`acid.models.econ2`,
``acid pulldown --econ-model econ2``).

- :func:`identify_new2`: the new record (today's econ record + the pull-downs, 60 s left out
  of each experiment's one-step stages) identified with :func:`acid.ident.econ.identify_slow`.
- :func:`validate_models`: the one-node and the two-node model open loop on the held-out
  pull-downs beside persistence, ARX and subspace (the same validator, windows and
  yardsticks as :func:`acid.studies.pulldown.validate_pair`), T_cab's mean signed error and
  p90 |error| per prediction time. The latent slow interior is carried from each held-out
  record's soaked start by its own equation driven by the measured interior
  (:func:`acid.models.econ2.slow_trace`): what a car can compute, no sensor of it needed.
- :class:`SlowInterior`: the economic NMPC on the two-node model. The NMPC is the econ
  model's (five states); the slow node enters its interior's equation as the additive
  derivative term the NMPC already takes (``dist``): ``hA_is (T_is - T_int) / C_int``, held
  over the 60 s horizon (the slow node's time constant is ~25 min: over 60 s its own
  temperature moves by < 0.1 K; the term moves with T_int, which this holds), ``T_is``
  carried from the soak by :func:`acid.models.econ2.slow_trace`'s recursion on the
  measured interior.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from acid.studies.pulldown import Models, PulldownSettings


def identify_new2(models: Models, new_skip_s: float = 60.0):
    """The two-node model on the new model's record (the old record and the pull-downs)."""
    from acid.data import Dataset
    from acid.ident.econ import identify_slow

    both = Dataset.concatenate([models.old_record, models.pulldown_record])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify_slow(both, skip_s=new_skip_s)


def _validate(name, params, ds, lo, settings):
    from acid.ident.validate import validate_model

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        v = validate_model(name, ds, params, starts=settings.validation_starts,
                           horizon=int(round(settings.validation_horizon_s / ds.Ts)),
                           warmup=0, start_range=(lo, len(ds)), estimation=(0, lo),
                           yardsticks=True, to_end=True)
    err = np.asarray(v.errors["T_cab"], dtype=float)
    row = {"bias": {}, "p90": {t: d["p90_K"] for t, d in v.by_time["T_cab"].items()},
           "n": {t: d["n"] for t, d in v.by_time["T_cab"].items()}}
    for t in row["p90"]:
        k = int(round(float(t) / ds.Ts)) - 1
        col = err[:, k] if k < err.shape[1] else np.array([math.nan])
        row["bias"][t] = float(np.nanmean(col)) if np.isfinite(col).any() else math.nan
    yard = {n: {t: d["p90_K"] for t, d in y.get("by_time", {}).get("T_cab", {}).items()}
            for n, y in v.yardsticks.items()}
    return row, yard


def validate_models(models: Models, fit2, held_out,
                    settings: PulldownSettings | None = None) -> dict:
    """{"econ": row, "econ2": row, "yardsticks": {name: {t: p90}}}: each row T_cab's mean
    signed error (predicted - measured) and p90 |error| (K) per prediction time on the
    held-out pull-downs, both models identified on the same record (old + pull-downs)."""
    from acid.data import Dataset
    from acid.ident.econ import with_slow_trace
    from acid.models import econ2
    from acid.models.values import ParameterValues

    settings = settings or PulldownSettings()
    ds = Dataset.concatenate([models.old_record, models.pulldown_record, held_out])
    lo = len(ds) - len(held_out)
    one, yard = _validate("econ", models.new, ds, lo, settings)
    ds2 = with_slow_trace(ds, fit2.C_is, fit2.hA_is)
    m = econ2.traced_model
    two, _ = _validate(m, ParameterValues(fit2.values, model=m, Ts=ds.Ts), ds2, lo, settings)
    return {"econ": one, "econ2": two, "yardsticks": yard}


class SlowInterior:
    """A controller (``make_step(meas, k)``, ``reset``) wrapping the engine's
    :class:`acid.studies.cav_study.EconPreview` on the two-node model's econ part: the slow
    interior carried from the soak and given to the NMPC as its interior's additive
    derivative term (module docstring)."""

    def __init__(self, preview, fit2, Ts: float):
        from acid.models import econ2

        self.preview, self.fit2, self.Ts = preview, fit2, float(Ts)
        self.mpc = preview.mpc
        self._a = math.exp(-fit2.hA_is * self.Ts / fit2.C_is)
        self._C_int = float(fit2.params.C_int)
        self._slow = econ2  # the recursion's source
        self.T_is = math.nan
        self._last_T_int = math.nan

    @property
    def log(self):
        return self.preview.log

    def reset(self) -> None:
        self.preview.reset()
        self.T_is, self._last_T_int = math.nan, math.nan

    def make_step(self, meas: dict, k: int) -> np.ndarray:
        from acid.studies.cav_study import stage_means

        T_int = float(meas["T_int"])
        if math.isnan(self.T_is):   # soaked (or settled): every interior mass alike
            self.T_is = T_int
        else:   # slow_trace's recursion, the interior held over the sample
            self.T_is = self._last_T_int + self._a * (self.T_is - self._last_T_int)
        self._last_T_int = T_int
        dist = np.zeros(5)
        dist[1] = self.fit2.hA_is * (self.T_is - T_int) / self._C_int
        p, iv, Ts = self.preview, self.mpc.config.intervals, self.preview.sc.Ts
        x = [meas[n] for n in ("T_cab", "T_int", "T_shell", "T_evap", "w_cab")]
        kw = {"T_cab_ref": p.setting} if p.comfort else {"T_cab_max": p.setting}
        return self.mpc.make_step(x, stage_means(p.v, k, iv, Ts),
                                  stage_means(p.T_amb, k, iv, Ts), dist=dist, **kw)
