"""acid: A/C system identification, validation and predictive climate control.

Reproduces and extends Wang, Kolmanovsky, Amini & Sun, "Model Predictive Climate Control of
Connected and Automated Vehicles for Improved Energy Efficiency" (ACC 2018).

Conventions (see ``ARCHITECTURE.md``): temperatures are kelvin inside every model and
solver, degrees Celsius in files, tables and figures; flows in kg/s, powers in W, speeds in
m/s, time in s. The sample time of the control-oriented model is ``Ts = 5 s``.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("acid")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.1.0"

__all__ = ["__version__"]
