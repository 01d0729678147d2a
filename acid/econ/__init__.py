"""The economic model family: cabin air, interior, shell, evaporator wall and cabin humidity,
with an identified compressor power map (beyond the paper; the paper's model in
:mod:`acid.model` stays the default).

* :mod:`acid.econ.params` -- ``EconParams`` and ``PowerMap`` (named, unit-carrying, JSON);
* :mod:`acid.econ.model` -- the model as pure functions (numpy and CasADi alike): the one
  source of truth for the fit, the simulator, the economic NMPC and the bound;
* :mod:`acid.econ.fit` -- ``EconFitter``: identification from excitation data
  (``acid fit --model econ``).
"""

from acid.econ.params import EconParams, PowerMap, load_any_params, model_family

__all__ = ["EconParams", "PowerMap", "load_any_params", "model_family"]
