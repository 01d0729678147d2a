"""A small user FMU for the tests (pythonfmu, FMI 2.0): not acid's plant, other units.

A first-order cabin lag with exact exponential integration, reported the way many tools
report: instantaneous values at the communication points, temperatures in degC, blower flow
in kg/h, compressor power in kW. ``stop_after`` (s) makes ``doStep`` refuse to go on, as an
FMU that terminates the simulation does.
"""

import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class CabinLag(Fmi2Slave):
    description = "first-order cabin lag (test FMU)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.W_bl_kgh = 360.0        # kg/h
        self.T_set_C = 5.0           # degC
        self.T_cab_C = 30.0          # degC
        self.T_cab0_C = 30.0
        self.tau = 50.0              # s
        self.stop_after = 1e9        # s
        self.time = 0.0
        for name in ("W_bl_kgh", "T_set_C"):
            self.register_variable(Real(name, causality=Fmi2Causality.input))
        for name in ("tau", "stop_after", "T_cab0_C"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.fixed))
        self.register_variable(Real("T_cab_C", causality=Fmi2Causality.output))
        self.register_variable(Real("T_int_C", causality=Fmi2Causality.output,
                                    getter=lambda: 28.0))
        self.register_variable(Real("T_shell_C", causality=Fmi2Causality.output,
                                    getter=lambda: 33.0))
        self.register_variable(Real("T_evap_C", causality=Fmi2Causality.output,
                                    getter=lambda: self.T_set_C))
        self.register_variable(Real("T_ain_C", causality=Fmi2Causality.output,
                                    getter=lambda: self.T_cab_C - 10.0))
        self.register_variable(Real("P_comp_kW", causality=Fmi2Causality.output,
                                    getter=lambda: 0.01 * self.W_bl_kgh / 3.6))

    def exit_initialization_mode(self):
        self.T_cab_C = self.T_cab0_C

    def do_step(self, current_time, step_size):
        if current_time + step_size > self.stop_after + 1e-9:
            return False
        a = math.exp(-step_size / self.tau)
        self.T_cab_C = self.T_set_C + (self.T_cab_C - self.T_set_C) * a
        self.time = current_time + step_size
        return True
