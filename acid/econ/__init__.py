"""The economic model's parameter files and the names its controllers read. The model itself
is declared once, in :mod:`acid.models.econ` (equations, parameter table, fitting stages).

* :mod:`acid.econ.params` -- ``EconParams`` (the declaration's table as a value container,
  JSON) with its ``PowerMap`` (domain, quality); ``identify`` (``acid fit --model econ``):
  acid.ident's staged fit of the declaration;

It is validated by acid's one validator, :func:`acid.ident.validate.validate`.
"""

from acid.econ.params import EconParams, PowerMap, load_any_params

__all__ = ["EconParams", "PowerMap", "load_any_params"]
