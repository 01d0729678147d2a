"""Values of the paper's model (eqs. 1-5): ``ModelParams``, acid's one parameter class
(``acid.models.values.ParameterValues``) bound to the declaration ``acid.models.paper``;
what the controllers, plants and parameter files use.

gamma1..gamma7 and tau1..tau3 parameterise eqs. 1-3 with **temperatures in kelvin** and W_bl
in kg/s at Ts = 5 s; beta1..beta3 the blower power curve (eq. 5, W with W_bl in kg/s).
``paper()`` is the set identified from CoolSim in the paper (section II-B-2 and eq. 5).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from acid.errors import DataError
from acid.models.paper import PARAMETER_TABLE as _DECLARED_TABLE
from acid.models.values import ParameterValues
from acid.paper import MODEL as _PAPER_MODEL
from acid.paper import TABLE_II as _TABLE_II

#: (name, unit, meaning) of every parameter, in the order of the vectors: the paper
#: declaration's table (``acid.models.paper``), the one parameter table.
PARAMETER_TABLE = _DECLARED_TABLE
# The paper's values live in the claims registry (the one place the paper's numbers are
# written); eq. 5's are also the econ model's start.
PAPER_BETA = _PAPER_MODEL.beta


class ModelParams(ParameterValues):
    """The values of the paper's declaration (``acid.models.paper``): ``ParameterValues``
    bound to it. ``p.gamma``, ``p.tau``, ``p.beta`` (tuples, ``PARAMETER_TABLE`` units,
    kelvin convention), ``p.c_p`` (J/(kg K)) and ``p.eta_cop`` (eq. 4's COP), ``p.Ts``."""

    MODEL = "paper"


def paper() -> ModelParams:
    """The paper's identified parameters (section II-B-2, eq. 5 and Table II), kelvin convention."""
    return ModelParams(gamma=_PAPER_MODEL.gamma, tau=_PAPER_MODEL.tau, beta=PAPER_BETA,
                       c_p=_TABLE_II.c_p, eta_cop=_TABLE_II.eta_cop, Ts=_TABLE_II.Ts,
                       name="paper", provenance={"source": "Wang et al., ACC 2018, section "
                                                           "II-B-2, eq. 5, Table II (acid.claims)"})


def load_params(spec: str | Path | None, allow_unstable: bool = False,
                binding: type = ModelParams) -> ModelParams:
    """``None`` or ``"paper"`` gives the paper preset; anything else is a parameter file of
    ``binding``'s model (``ParameterValues``: of the model the file names, as its binding).

    Implausible values (the declaration's ``checks``) are refused with a one-line
    ``DataError`` unless ``allow_unstable``.
    """
    if spec is None or str(spec) == "paper":
        return paper()
    p = binding.from_json(spec)
    return p if allow_unstable else p.check(str(spec))


def fitted(result, eta_cop: float | None = None, name: str | None = None,
           provenance: dict | None = None) -> ModelParams:
    """The paper's parameters from a fit of its declaration (``acid.ident.fit_model(
    "paper", ...)``); ``eta_cop`` replaces Table II's COP (eq. 4, e.g. ``eta_cop_of``)."""
    changes = {} if eta_cop is None or not math.isfinite(eta_cop) or eta_cop <= 0 \
        else {"eta_cop": float(eta_cop)}
    return paper().with_theta(np.asarray(result.values, dtype=float),
                              name=name or f"fit-{result.method}",
                              provenance=dict(provenance or {}), **changes)


def eta_cop_of(ds, c_p: float = _TABLE_II.c_p) -> tuple[float, float]:
    """eta_cop and its standard error from a dataset's P_comp, T_amb, W_bl and T_ain (eq. 4,
    ``acid.models.paper.estimate_eta_cop``); NaN when the data lack a channel."""
    from acid.models.paper import estimate_eta_cop

    if not all(n in ds for n in ("P_comp", "T_amb", "W_bl", "T_ain")):
        return math.nan, math.nan
    return estimate_eta_cop(ds.get("W_bl", "kg/s"), ds.get("T_ain", "K"), ds.get("T_amb", "K"),
                            ds.get("P_comp", "W"), c_p)


def as_params(obj) -> ModelParams:
    """The model parameters of ``obj``: a ``ModelParams`` as is, a fit of the paper's
    declaration (``acid.ident.fit_model``'s result, or anything with ``params``),
    ``None``/``"paper"`` for the preset or a params.json path.
    """
    if isinstance(obj, ModelParams):
        return obj
    inner = getattr(obj, "params", None)
    if isinstance(inner, ModelParams):
        return inner
    if getattr(obj, "model", None) == "paper" and hasattr(obj, "values"):
        return fitted(obj)
    if obj is None or isinstance(obj, (str, Path)):
        return load_params(obj)
    raise DataError(f"expected model parameters (ModelParams, a fit result or a params.json "
                    f"path), got {type(obj).__name__}")
