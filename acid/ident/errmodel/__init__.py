"""Grey box plus what it misses: an ARX error model on a declared model's residual.

A declared (grey-box) model keeps its physical parameters; what it systematically misses
on the channel scored (e.g. T_cab) is modelled by a linear ARX model of its open-loop
residual ``r = measured - predicted`` driven by the model's inputs and disturbances:

    r(i) = c + sum_{l=1..na} a_l r(i - l) + sum_{j=0..nb-1} b_j u(i - j)

fitted by least squares (``acid.ident.yardsticks.fit_arx``, the ARX yardstick's code) on
the residual of the declared model's windows placed on the **estimation** samples only,
orders chosen among 1..4 by open-loop error over those windows. At a validation start the
residual at step 0 (measured minus the model's start value, known at the start) seeds the
ARX, which then runs open loop over the window (steps before 0 repeat step 0); the
prediction is the grey box's plus the residual model's. The corrected errors are scored
like the model's (``acid.ident.crossval.interval_tables``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acid.errors import ConfigError, DataError
from acid.ident.yardsticks import ARX, ARX_ORDERS, PAST_SAMPLES, fit_arx

#: Below this standard deviation a signal counts as constant (left out of the inputs).
_CONSTANT_STD = 1e-9


@dataclass(frozen=True)
class ResidualModel:
    """A fitted residual ARX on one channel of a declared model (standardised inside).

    ``arx``: the model; ``y_mean``/``y_std`` the residual's scaling, ``u_mean``/``u_std``
    the inputs' (``use`` which inputs, by index into the validation's inputs);
    ``settings``: channel, orders tried and scores, windows and samples it was fitted on.
    """

    channel: str
    arx: ARX
    y_mean: float
    y_std: float
    u_mean: np.ndarray
    u_std: np.ndarray
    use: np.ndarray
    settings: dict = field(default_factory=dict)

    def predict(self, r0: np.ndarray, inputs: np.ndarray) -> np.ndarray:
        """(S, H + 1) residual predicted from its step-0 value ``r0`` (S,) and the window's
        inputs ``inputs`` (S, H + 1, nu): step 0 is ``r0``."""
        lag = self.arx.lag
        u = (inputs[..., self.use] - self.u_mean) / self.u_std
        S, T = u.shape[:2]
        uw = np.concatenate([np.repeat(u[:, :1], lag, axis=1), u], axis=1)
        yw = np.zeros((S, lag + T, 1))
        yw[:, :lag + 1, 0] = ((r0 - self.y_mean) / self.y_std)[:, None]
        out = self.arx.simulate(yw, uw, lag)[:, lag:, 0]
        return out * self.y_std + self.y_mean


def _inputs_of(res) -> np.ndarray:
    if res.inputs is None:
        raise DataError("the validation carries no inputs: the error model needs them")
    S, T = res.inputs.shape[:2]
    return res.inputs.reshape(S, T, -1)


def residual_windows(res, channel: str) -> tuple[np.ndarray, np.ndarray]:
    """(S, H + 1) residual ``measured - predicted`` of ``channel`` over a validation's
    windows, and (S, H + 1, nu) their inputs."""
    if channel not in res.channels:
        raise ConfigError(f"error model: channel {channel!r} is not scored by the validation "
                          f"(scored: {', '.join(res.channels)})")
    c = res.channels.index(channel)
    r = res.measured[..., c] - res.predicted[..., c]
    return r, _inputs_of(res)


def fit_residual_model(res, channel: str, orders=ARX_ORDERS) -> ResidualModel:
    """Fit the residual ARX on the windows of ``res``, a ``DeclaredValidation`` whose starts
    all lie on estimation samples (e.g. ``validate_model(..., start_range=(0, n_est))``)."""
    r, u = residual_windows(res, channel)
    fin = np.isfinite(r) & np.all(np.isfinite(u), axis=2)
    length = np.where(fin.all(axis=1), r.shape[1], np.argmin(fin, axis=1))  # finite prefix
    need = max(orders) + 2
    keep = length >= need
    if keep.sum() < 3:
        raise DataError(f"error model: {int(keep.sum())} estimation windows of {channel!r} "
                        f"with {need} scored steps from the start; at least 3 are needed")
    r, u, length = r[keep], u[keep], length[keep]
    S, T = r.shape
    seen = np.arange(T)[None, :] < length[:, None]
    flat_u = u[seen]
    u_std = flat_u.std(axis=0)
    use = np.flatnonzero(u_std > _CONSTANT_STD)
    u_mean, u_std = flat_u[:, use].mean(axis=0), u_std[use]
    y_mean, y_std = float(r[seen].mean()), float(r[seen].std()) or 1.0
    z = np.where(seen, (r - y_mean) / y_std, 0.0)[..., None]
    v = np.where(seen[..., None], (u[..., use] - u_mean) / u_std, 0.0)
    segs = [(i * T, i * T + int(n)) for i, n in enumerate(length)]
    # orders by open-loop error from step 0 of the windows reaching ``span`` steps (the
    # task it is used for); the open-loop score starts after PAST_SAMPLES samples
    span = int(np.sort(length)[-3]) if (length >= T).sum() < 3 else T
    full = length >= span
    pad = PAST_SAMPLES
    sel = (np.concatenate([np.repeat(z[full, :1], pad, axis=1), z[full, :span]], axis=1),
           np.concatenate([np.repeat(v[full, :1], pad, axis=1), v[full, :span]], axis=1))
    arx, scores = fit_arx(z.reshape(S * T, 1), v.reshape(S * T, -1), segs, orders, sel)
    return ResidualModel(channel, arx, y_mean, y_std, u_mean, u_std, use,
                         {"channel": channel, "na": arx.na, "nb": arx.nb,
                          "stable": arx.stable, "windows": int(S), "samples": int(length.sum()),
                          "scores": scores, "inputs_used": use.tolist()})


def corrected_errors(res, em: ResidualModel) -> np.ndarray:
    """(S, H) errors (prediction minus measurement, steps 1..H) of the grey box plus the
    residual model on the windows of ``res`` (NaN where the model's are)."""
    r, u = residual_windows(res, em.channel)
    c = res.channels.index(em.channel)
    rhat = em.predict(np.nan_to_num(r[:, 0]), np.nan_to_num(u))
    return res.errors[res.channels[c]] + rhat[:, 1:]


@dataclass(frozen=True)
class ErrorModelValidation:
    """Held-out validation of a declared model with and without its residual model.

    ``errors[predictor]`` (starts, horizon): ``"model"`` (grey box plus residual ARX),
    ``"greybox"`` (the declared model alone) and the yardsticks, on the same held-out windows;
    ``experiment`` each start's experiment index into ``names``; ``intervals`` the
    figures and verdicts of ``model`` against the others (``interval_tables``)."""

    channel: str
    errors: dict
    experiment: np.ndarray
    names: tuple[str, ...]
    residual: ResidualModel
    Ts: float
    figures: tuple = ()
    verdicts: tuple = ()


def validate_with_error_model(model, ds, params, *, n_estimation: int, channel: str | None = None,
                              fit_starts: int = 120, times_s=(60.0, 300.0, 600.0, 1500.0),
                              n_resamples: int = 1000, seed: int = 0,
                              **validate_options) -> ErrorModelValidation:
    """Fit the residual ARX on windows of the first ``n_estimation`` samples of ``ds`` (the
    estimation experiments), then validate on the rest with the yardsticks fitted on the
    same estimation samples; ``validate_options`` go to ``validate_model`` (horizon,
    starts, to_end, hold, warm_start...)."""
    from acid.ident.crossval import interval_tables
    from acid.ident.validate import validate_model

    opts = {"hold": (), **validate_options}
    est = validate_model(model, ds, params, **{**opts, "starts": fit_starts, "start_index": None},
                         start_range=(0, n_estimation), yardsticks=False)
    ch = channel or next((c for c, u in zip(est.channels, est.units, strict=True) if u == "K"),
                         est.channels[0])
    em = fit_residual_model(est, ch)
    res = validate_model(model, ds, params, **opts, start_range=(n_estimation, len(ds)),
                         yardsticks=True, estimation=(0, n_estimation))
    errors = {"model": corrected_errors(res, em), "greybox": res.errors[ch],
              **{k: y["errors"][ch] for k, y in res.yardsticks.items()
                 if ch in y.get("errors", {})}}
    names = tuple(ds.experiment_names())
    exp = np.asarray(ds.experiment)[res.starts]
    errors = {k: np.where(np.isfinite(errors["greybox"]), e, np.nan) for k, e in errors.items()}
    figs, verdicts = interval_tables(errors, exp, names, res.Ts, times_s,
                                     n_resamples=n_resamples, seed=seed)
    return ErrorModelValidation(ch, errors, exp, names, em, res.Ts, figs, verdicts)


def summary(v: ErrorModelValidation, scopes=("pooled",)) -> str:
    """Pooled (or per-experiment) RMSE / p90 with intervals and verdicts, as text."""
    st = v.residual.settings
    lines = [f"{v.channel}: grey box plus residual ARX (na={st['na']}, nb={st['nb']}, fitted on "
             f"{st['windows']} estimation windows, {st['samples']} samples); 95 % intervals"]
    for f in v.figures:
        if f.scope in scopes:
            flag = "" if f.resolved else "  not resolved"
            lines.append(f"  {f.scope:>8} {f.time_s:6g} s {f.predictor:>12}: RMSE {f.rmse:.2f} "
                         f"[{f.rmse_lo:.2f}, {f.rmse_hi:.2f}]  p90 {f.p90:.2f} "
                         f"[{f.p90_lo:.2f}, {f.p90_hi:.2f}]  {f.n_starts} starts / "
                         f"{f.n_experiments} exp.{flag}")
    for d in v.verdicts:
        if d.scope in scopes:
            lines.append(f"  {d.scope:>8} {d.time_s:6g} s grey box + ARX vs {d.yardstick}: "
                         f"{d.verdict}, {d.difference:+.2f} [{d.lo:+.2f}, {d.hi:+.2f}] K")
    return "\n".join(lines)

