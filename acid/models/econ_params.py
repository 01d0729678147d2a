"""The econ model's values (``EconParams``: acid's one parameter class bound to the
declaration :mod:`acid.models.econ`); its identification is :func:`acid.ident.econ.identify`.
A parameter file names its model; :func:`load_any_params` reads any.
"""

from __future__ import annotations

from acid.models import econ
from acid.models.econ import MAP_INPUTS, MAP_TERMS, PowerMap  # noqa: F401 (re-exported)
from acid.models.params import load_params
from acid.models.values import ParameterValues

MODEL_NAME = "econ"
#: The thermal parameters' names (the declaration's table, ``acid.models.econ``).
NAMES: tuple[str, ...] = econ.THERMAL_NAMES


class EconParams(ParameterValues):
    """The values of the econ declaration (``acid.models.econ``): ``ParameterValues`` bound
    to it. By name (``p.C_cab``, SI, K), ``p.beta`` (eq. 5), ``p.power_map`` (its
    ``PowerMap`` with the domain of the identification data) and ``p.theta_all``."""

    MODEL = MODEL_NAME


def load_any_params(spec, allow_unstable: bool = False):
    """``load_params`` for the file of any declared model (``EconParams`` for the econ
    model's, ``ModelParams`` for the paper's...)."""
    return load_params(spec, allow_unstable, ParameterValues)
