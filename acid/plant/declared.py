"""Any declared model as a plant (the protocol of :mod:`acid.plant.base`), so that
``acid.excite`` records data from it: a plant whose true parameters are known.

Each step evaluates the declaration's one-sample map ``model.F`` with the inputs held. The
schedule gives W_bl, T_evap_set, v_veh and, when set, T_int, T_shell, T_amb; a declared
input or disturbance the schedule does not give is held at its ``constant`` value (K for
temperatures). Row k carries the states at t_k (latent ones too, as the truth), the inputs,
the disturbances and the outputs over the interval.

Options for any declaration: a disturbance the schedule gives holds until it gives the next
one (its value at reset comes from ``initial``); white measurement noise on the temperature
channels and process noise on the states (a seeded ``rng``); channels ``derived`` from each
row (the paper's eq. 4 compressor power); outputs ``floor``ed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from acid.errors import ConfigError
from acid.models.declaration import Model
from acid.models.loader import load
from acid.plant.base import Measurement, Plant


class DeclaredPlant(Plant):
    """A declared model (``Model``, a built-in name or a model file) as a plant.

    Parameters
    ----------
    model : the declaration.
    values : parameter values (np,), default the declared ones.
    initial : {state: value} at reset (default: ``T_amb`` for temperature states, else 0).
    constant : {signal: value} for inputs/disturbances no schedule provides.
    T_amb : ambient temperature, K (a disturbance named T_amb when the schedule has none).
    floor : {output: the lowest value the plant reports} (``{"P_comp": 0.0}``: a compressor
        draws no negative power where a smooth model's map would).
    meas_noise_std : std of white noise added to the recorded ``noisy`` channels, K.
    process_noise_std : std of white noise added to every state after each step, K.
    rng : random generator of the noise (seed it for reproducible data).
    noisy : channels the measurement noise is added to (default: the measured states and
        the outputs in K, in declared order).
    derived : ``f(row, given) -> {channel: value}`` recorded beside the declared channels
        (``given``: the step's inputs and disturbances, T_amb and v_veh included).
    name : the plant's name in dataset metadata; ``info``: more of its ``config()``.
    """

    name = "declared-model"

    def __init__(self, model: Model | str, values=None, initial: dict | None = None,
                 constant: dict | None = None, T_amb: float = 303.15,
                 floor: dict | None = None, *, meas_noise_std: float = 0.0,
                 process_noise_std: float = 0.0, rng: np.random.Generator | None = None,
                 noisy: tuple[str, ...] | None = None, derived=None,
                 name: str | None = None, info: dict | None = None):
        self.model = load(model)
        if name is not None:
            self.name = name
        self.meas_noise_std = float(meas_noise_std)
        self.process_noise_std = float(process_noise_std)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.noisy = tuple(noisy) if noisy is not None else tuple(
            r.name for r in [*(s for s in self.model.states if s.measured), *self.model.outputs]
            if r.unit == "K")
        self.derived = derived
        self.info = dict(info or {})
        self.floor = {n: float(v) for n, v in (floor or {}).items()}
        unknown = sorted(set(self.floor) - set(self.model.output_names))
        if unknown:
            raise ConfigError(f"model {self.model.name!r}: floor of {unknown[0]!r}, not an "
                              f"output ({', '.join(self.model.output_names)})")
        m = self.model
        self.values = m.values if values is None else np.asarray(values, dtype=float)
        if self.values.shape != (m.np,):
            raise ConfigError(f"model {m.name!r}: {m.np} parameter values needed, got "
                              f"{self.values.shape}")
        self.Ts = m.Ts
        self.T_amb0 = float(T_amb)
        self.constant = {"T_amb": self.T_amb0, "v_veh": 0.0, **(constant or {})}
        self._initial = dict(initial or {})
        self.reset()

    @property
    def INITIAL_KEYS(self) -> tuple[str, ...]:  # noqa: N802 - the protocol's name
        """States and disturbances (a disturbance's value until a schedule gives one)."""
        return (*self.model.state_names, *self.disturbance_names)

    def __getattr__(self, name: str):
        """A state by its name (``plant.T_cab``), K for temperatures."""
        states = self.__dict__.get("model").state_names if "model" in self.__dict__ else ()
        if name in states and "x" in self.__dict__:
            return float(self.x[states.index(name)])
        raise AttributeError(name)

    def __setattr__(self, name: str, value) -> None:
        """Setting a state by its name moves the plant there (a disturbance a test adds)."""
        model = self.__dict__.get("model")
        if model is not None and name in model.state_names and "x" in self.__dict__:
            x = self.x.copy()
            x[model.state_names.index(name)] = float(value)
            self.x = x
        else:
            super().__setattr__(name, value)

    def config(self) -> dict:
        noise = {"meas_noise_std_K": self.meas_noise_std,
                 "process_noise_std_K": self.process_noise_std} \
            if self.meas_noise_std or self.process_noise_std else {}
        return {"model": self.model.name, "model_source": self.model.source,
                "parameters": dict(zip(self.model.parameter_names, self.values.tolist(),
                                       strict=True)), "constant": self.constant,
                **noise, **self.info}

    def units(self) -> dict[str, str]:
        rows = self.model.states + self.model.inputs + self.model.disturbances + \
            self.model.outputs
        return {r.name: r.unit for r in rows}

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        init = {**self._initial, **(initial or {})}
        unknown = [k for k in init if k not in self.INITIAL_KEYS]
        if unknown:
            raise ConfigError(f"initial condition {unknown[0]!r} unknown (states and "
                              f"disturbances of {self.model.name!r}: "
                              f"{', '.join(self.INITIAL_KEYS)})")
        self.x = np.array([float(init.get(s.name, self.T_amb0 if s.unit == "K" else 0.0))
                           for s in self.model.states])
        self.held = {k: float(v) for k, v in init.items() if k in self.disturbance_names}
        self.T_amb = self.T_amb0
        return self.measure()

    def measure(self) -> Measurement:
        """States (noise-free), the held disturbances and T_amb."""
        return {**dict(zip(self.model.state_names, map(float, self.x), strict=True)),
                **self.held, "T_amb": self.T_amb}

    @property
    def disturbance_names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.model.disturbances)

    def check_schedule(self, schedule) -> None:
        """One line naming every declared input or disturbance that neither ``schedule``
        (an ``acid.plant.base.InputSchedule``) nor ``constant`` gives."""
        given = {"W_bl", "T_evap_set", "v_veh", "T_amb", *self.constant, *self._initial}
        given |= {n for n in ("T_int", "T_shell") if getattr(schedule, n, None) is not None}
        missing = [r.name for r in self.model.inputs + self.model.disturbances
                   if r.name not in given]
        if missing:
            raise ConfigError(
                f"{Path(self.model.source).name}: model {self.model.name!r} declares "
                f"{', '.join(map(repr, missing))}, which no excitation schedule gives (it "
                f"drives {', '.join(sorted(given))}"
                + ("; T_int and T_shell with --vary-exogenous" if {"T_int", "T_shell"} &
                   set(missing) else "") + ")")

    def _signal(self, name: str, given: dict) -> float:
        if name in given:
            return float(given[name])
        if name in self.held:
            return self.held[name]
        if name in self.constant:
            return float(self.constant[name])
        raise ConfigError(f"model {self.model.name!r}: no schedule gives {name!r}; pass "
                          f"constant={{{name!r}: value}}")

    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **exo) -> Measurement:
        if "T_amb" in exo:
            self.T_amb = float(exo["T_amb"])
        # a disturbance given holds until the next one
        self.held.update({n: float(exo[n]) for n in self.disturbance_names
                          if n in exo and n not in ("T_amb", "v_veh")})
        given = {"W_bl": W_bl, "T_evap_set": T_evap_set, "v_veh": v_veh, **exo,
                 "T_amb": self.T_amb}
        m = self.model
        u = [self._signal(r.name, given) for r in m.inputs]
        d = [self._signal(r.name, given) for r in m.disturbances]
        row = dict(zip(m.state_names, map(float, self.x), strict=True))
        x_next, y = m.step(self.x, u, d, self.values)
        self.x = x_next
        row.update(zip((r.name for r in m.inputs), u, strict=True))
        row.update(zip((r.name for r in m.disturbances), d, strict=True))
        row.update(zip(m.output_names, map(float, y), strict=True))
        if self.derived is not None:
            row.update(self.derived(row, given))
        row.update({n: max(row[n], v) for n, v in self.floor.items()})
        if self.meas_noise_std:
            noise = self.rng.standard_normal(len(self.noisy)) * self.meas_noise_std
            for name, n in zip(self.noisy, noise, strict=True):
                row[name] += n
        if self.process_noise_std:
            self.x = self.x + self.rng.standard_normal(m.nx) * self.process_noise_std
        return row


def paper_plant(params=None, T_amb: float = 303.15, meas_noise_std: float = 0.0,
                process_noise_std: float = 0.0, rng=None):
    """Eqs. 1-3 and 5 as a plant (``acid.plant.declared.DeclaredPlant``, named ``"model"``):
    T_int and T_shell held at their initial values until a schedule gives them; P_comp from
    eq. 4 at the ambient ``T_amb`` (K, Table II: 30 degC); noise in K on T_cab, T_evap, T_ain.

    ``params``: ``ModelParams`` or a fit of this declaration (the paper preset by default).
    """
    from acid.models.paper import PLANT_INITIAL, compressor_power, model
    from acid.models.params import as_params, paper

    p = paper() if params is None else as_params(params)

    def eq4(row, given):
        return {"T_amb": given["T_amb"], "v_veh": float(given["v_veh"]),
                "P_comp": max(0.0, float(compressor_power(float(row["W_bl"]), row["T_ain"],
                                                          given["T_amb"], p.c_p, p.eta_cop)))}

    out = DeclaredPlant(model, p.theta, initial=PLANT_INITIAL, T_amb=float(T_amb),
                        meas_noise_std=meas_noise_std, process_noise_std=process_noise_std,
                        rng=rng, derived=eq4, name="model",
                        info={"params": p.to_json_dict(), "T_amb_K": float(T_amb)})
    out.params = p   # the ModelParams it runs (the controllers' tests compare them)
    return out


def econ_plant(theta=None, **kw):
    """The econ model as a plant (:class:`acid.plant.declared.DeclaredPlant`) at the parameter
    vector ``theta`` (default: declared), started hot-soaked, the compressor power map
    floored at zero (``kw`` as ``DeclaredPlant``'s)."""
    from acid.models.econ import HOT_SOAK, model

    return DeclaredPlant(model, theta, **{"initial": HOT_SOAK, "floor": {"P_comp": 0.0},
                                          **kw})
