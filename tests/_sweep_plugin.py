"""A controller that raises in hot scenarios: how a failing scenario looks to a sweep.

Imported by the spec's ``plugins = ["_sweep_plugin"]`` (in the test process and, through the
constructor's reference, on the Dask workers, which inherit ``sys.path``).
"""

from __future__ import annotations

from dataclasses import dataclass

from acid.studies.sweep.controllers import PaperNMPC, PaperNMPCConfig, register_controller


@dataclass(frozen=True)
class FragileConfig:
    """``above_C``: ambient temperature (degC) from which the controller raises."""

    above_C: float = 40.0


class Fragile:
    """The paper NMPC on the set-point, except that it raises when it is too hot."""

    def __init__(self, config: FragileConfig):
        self.config = config

    def run(self, ctx):
        if ctx.conditions.ambient_C >= self.config.above_C:
            raise RuntimeError(f"too hot for this controller ({ctx.conditions.ambient_C:g} C)")
        return PaperNMPC(PaperNMPCConfig()).run(ctx)


register_controller("fragile", FragileConfig, Fragile, "raises above an ambient temperature")
