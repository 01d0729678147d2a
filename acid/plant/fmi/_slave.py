"""The FMU slave of ``acid export-fmu``: acid's high-fidelity plant behind the FMI API.

This file is copied into the FMU (``resources/<ModelIdentifier>.py``) by
:func:`acid.plant.fmi.export.export_fmu`, which sets ``FMI_VERSION`` and the class name; it
is not imported as part of acid. It runs in the Python that loads the FMU (pythonfmu /
pythonfmu3 embed the interpreter), which must have acid installed.

What the FMU exposes is read from ``resources/acid_plant.json`` (written at export time from
a probe of the plant): the plant configuration, the state channels (``HifiPlant.measure``)
and the channels that are means over a step. Variables (temperatures in K, SI units):

* inputs ``input.W_bl``, ``input.T_evap_set``, ``input.v_veh``, ``input.T_amb``,
  ``input.T_cab_set`` (Real) and ``input.compressor_enabled`` (Boolean), held over a step;
* parameters ``start.<key>`` (initial conditions of ``HifiPlant.reset``) and ``nominal``
  (Boolean: the plant's own nominal controller sets blower and compressor);
* outputs ``state.<channel>``: the states at the current communication point;
  ``mean.<channel>``: means over the last communication step (the sample convention).

The plant is built when initialisation ends, with the ambient temperature of
``input.T_amb`` at that moment as its configured ambient, and rebuilt once at the first
``doStep`` with its sample time equal to the communication step (which must be a multiple of
the internal step ``dt_int``). Errors raise: the FMI status is then fatal and the message is
logged.
"""

import json
from pathlib import Path

FMI_VERSION = 2  # replaced at export

if FMI_VERSION == 3:
    from pythonfmu3 import Boolean, Fmi3Slave
    from pythonfmu3 import Float64 as RealVariable
    from pythonfmu3 import Fmi3Causality as Causality
    from pythonfmu3 import Fmi3Variability as Variability

    Slave = Fmi3Slave
else:
    from pythonfmu import Boolean, Fmi2Slave
    from pythonfmu import Fmi2Causality as Causality
    from pythonfmu import Fmi2Variability as Variability
    from pythonfmu import Real as RealVariable

    Slave = Fmi2Slave

SPEC_FILE = "acid_plant.json"


class AcidHifiPlant(Slave):
    """acid's high-fidelity A/C + cabin plant as a co-simulation FMU."""

    author = "acid"
    description = "acid high-fidelity A/C + cabin plant (CoolProp cycle, thermal masses)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        spec = json.loads((Path(self.resources) / SPEC_FILE).read_text())
        self.spec = spec
        self.inputs = dict(spec["inputs"])          # name -> value (SI)
        self.compressor_enabled = True
        self.nominal = False
        self.starts = dict(spec["initial"])          # key -> default value
        self.starts_given = {}                       # keys the importer set
        self.states = dict(spec["state_values"])     # channel -> value at the current point
        self.means = {k: 0.0 for k in spec["means"]}
        self.plant = None
        self.plant_Ts = None
        self.time = 0.0
        units = spec["units"]
        if FMI_VERSION == 3:
            self.register_variable(RealVariable("time", causality=Causality.independent,
                                                variability=Variability.continuous))

        def real(name, unit, **kw):
            if FMI_VERSION == 3:
                return RealVariable(name, unit=unit, **kw)
            return RealVariable(name, **kw)

        for key in self.inputs:
            self.register_variable(real(
                f"input.{key}", units[key], causality=Causality.input,
                getter=lambda k=key: self.inputs[k],
                setter=lambda v, k=key: self.inputs.__setitem__(k, float(v))))
        self.register_variable(Boolean(
            "input.compressor_enabled", causality=Causality.input,
            variability=Variability.discrete, getter=lambda: self.compressor_enabled,
            setter=lambda v: setattr(self, "compressor_enabled", bool(v))))
        for key in self.starts:
            self.register_variable(real(
                f"start.{key}", units[key], causality=Causality.parameter,
                variability=Variability.fixed, getter=lambda k=key: self.starts[k],
                setter=lambda v, k=key: self._set_start(k, v)))
        self.register_variable(Boolean(
            "nominal", causality=Causality.parameter, variability=Variability.fixed,
            getter=lambda: self.nominal, setter=lambda v: setattr(self, "nominal", bool(v))))
        for key in self.states:
            self.register_variable(real(f"state.{key}", units[key], causality=Causality.output,
                                        getter=lambda k=key: self.states[k]))
        for key in self.means:
            self.register_variable(real(f"mean.{key}", units[key], causality=Causality.output,
                                        getter=lambda k=key: self.means[k]))

    def _set_start(self, key, value):
        self.starts[key] = float(value)
        self.starts_given[key] = float(value)

    def _build(self, Ts=None):
        from acid.plant.config import PlantConfig
        from acid.plant.hifi import HifiPlant

        cfg = PlantConfig.from_dict(self.spec["config"], source="FMU configuration")
        changes = {"T_amb": self.inputs["T_amb"]}
        if Ts is not None:
            changes["Ts"] = Ts
        plant = HifiPlant(cfg.replace(**changes), mode="nominal" if self.nominal else "direct")
        plant.reset(self.starts_given or None)
        return plant

    def exit_initialization_mode(self):
        self.plant = self._build()
        self.plant_Ts = self.plant.Ts
        self.states.update({k: float(v) for k, v in self.plant.measure().items()
                            if k in self.states})

    def do_step(self, current_time, step_size):
        h = float(step_size)
        if self.plant is None:
            raise RuntimeError("doStep before initialisation")
        if abs(h - self.plant_Ts) > 1e-9 * max(1.0, h):
            if self.time > 0.0:
                raise RuntimeError(f"communication step changed from {self.plant_Ts:g} s to "
                                   f"{h:g} s (keep it constant)")
            self.plant = self._build(Ts=h)
            self.plant_Ts = h
        kw = {"T_amb": self.inputs["T_amb"], "compressor_enabled": self.compressor_enabled}
        if self.nominal:
            kw["T_cab_set"] = self.inputs["T_cab_set"]
        row = self.plant.step(self.inputs["W_bl"], self.inputs["T_evap_set"],
                              self.inputs["v_veh"], **kw)
        for key in self.means:
            self.means[key] = float(row[key])
        now = self.plant.measure()
        for key in self.states:
            self.states[key] = float(now[key])
        self.time = float(current_time) + h
        return True
