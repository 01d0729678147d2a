"""acid: A/C system identification, validation and predictive climate control.

Reproduces and extends Wang, Kolmanovsky, Amini & Sun, "Model Predictive Climate Control of
Connected and Automated Vehicles for Improved Energy Efficiency" (ACC 2018).

Conventions (see ``ARCHITECTURE.md``): temperatures are kelvin inside every model and
solver, degrees Celsius in files, tables and figures; flows in kg/s, powers in W, speeds in
m/s, time in s. The sample time of the control-oriented model is ``Ts = 5 s``.

The main objects are available here, imported on first use (``import acid`` stays light)::

    import acid
    plant = acid.make_plant("hifi", T_amb=acid.degC(35))       # or "fmu:my.fmu", fmu_map=...
    data = acid.excite(plant, acid.ExcitationSpec(duration=3600, seed=1))
    est, val = data.split(0.5)
    result = acid.fit(est, method="oe")
    acid.compare(val, result, acid.paper_params()).to_frame()

Temperatures given to the Python API: a plain number is in the documented unit of its
argument (kelvin, except the degC bounds of ``ExcitationSpec``); ``acid.degC(25)`` and
``acid.kelvin(298.15)`` are unit-aware values accepted by either.
"""

import sys
import types
from importlib import import_module
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("acid")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.1.0"

#: public name -> (module, attribute): resolved lazily by ``__getattr__`` (PEP 562)
_API = {
    # units
    "degC": ("acid.units", "degC"), "kelvin": ("acid.units", "kelvin"),
    "C2K": ("acid.units", "C2K"), "K2C": ("acid.units", "K2C"),
    # datasets
    "Dataset": ("acid.data", "Dataset"), "ChannelMap": ("acid.data", "ChannelMap"),
    "load_dataset": ("acid.data", "Dataset.from_hdf5"), "from_csv": ("acid.data", "from_csv"),
    "from_mat": ("acid.data", "from_mat"), "drive_cycle": ("acid.signals", "drive_cycle"),
    "import_logs": ("acid.data", "import_logs"), "example": ("acid.examples", "resolve"),
    # parameters
    "ModelParams": ("acid.models.params", "ModelParams"),
    "paper_params": ("acid.models.params", "paper"),
    "load_params": ("acid.models.params", "load_params"),
    # excitation
    "ExcitationSpec": ("acid.excite", "ExcitationSpec"), "excite": ("acid.excite", "excite"),
    "make_schedule": ("acid.excite", "make_schedule"),
    "InputSchedule": ("acid.plant.base", "InputSchedule"),
    # plants
    "make_plant": ("acid.plant", "make_plant"), "Plant": ("acid.plant.base", "Plant"),
    "HifiPlant": ("acid.plant.hifi", "HifiPlant"), "PlantConfig": ("acid.plant.config",
                                                                   "PlantConfig"),
    "ModelPlant": ("acid.plant", "ModelPlant"),
    "HeatingPlant": ("acid.plant.heating", "HeatingPlant"),
    "HeatingConfig": ("acid.plant.heating_config", "HeatingConfig"),
    "FmuPlant": ("acid.plant.fmi.plant", "FmuPlant"), "FmuMap": ("acid.plant.fmi.plant", "FmuMap"),
    "export_fmu": ("acid.plant.fmi.export", "export_fmu"),
    "speed_sweep": ("acid.plant.sweep", "speed_sweep"),
    # identification and validation
    "fit": ("acid.ident.fit", "fit"), "FitResult": ("acid.ident.fit", "DeclaredFitResult"),
    "validate": ("acid.ident.validate", "validate"),
    "ValidationResult": ("acid.ident.validate", "DeclaredValidation"),
    "predict": ("acid.ident.analysis", "predict"), "compare": ("acid.ident.analysis", "compare"),
    "resid": ("acid.ident.analysis", "resid"),
    # declared models (acid.models) and the identification derived from them (acid.ident)
    "Model": ("acid.models", "Model"), "load_model": ("acid.models", "load"),
    "fit_model": ("acid.ident.fit", "fit_model"),
    "validate_model": ("acid.ident.validate", "validate_model"),
    # control
    "NMPC": ("acid.control.nmpc", "NMPC"), "NMPCConfig": ("acid.control.nmpc", "NMPCConfig"),
    "closed_loop": ("acid.studies.mpc_check.scenarios", "closed_loop"),
    "mpc_check": ("acid.studies.mpc_check.scenarios", "mpc_check"),
}

__all__ = ["__version__", *_API]


def __getattr__(name: str):
    try:
        module, attr = _API[name]
    except KeyError:
        raise AttributeError(f"module 'acid' has no attribute {name!r}") from None
    obj = import_module(module)
    for part in attr.split("."):
        obj = getattr(obj, part)
    globals()[name] = obj
    return obj


def __dir__():
    return sorted(set(globals()) | set(_API))


class _Package(types.ModuleType):
    """``acid`` whose exported functions stay functions when a submodule of the same name
    is imported (``import acid.excite`` would otherwise replace ``acid.excite()``, the
    function, by the module ``acid.excite``: "'module' object is not callable")."""

    def __setattr__(self, name, value):
        if isinstance(value, types.ModuleType) and name in _API \
                and value.__name__ == _API[name][0] and _API[name][1] != "":
            return   # the submodule stays reachable as sys.modules["acid.<name>"]
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
