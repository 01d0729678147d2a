"""Moved to :mod:`acid.models.econ_params`: this alias package warns, and goes in the next
release. Its modules are aliases of the new ones."""

import warnings

from acid.errors import MovedWarning
from acid.models.econ_params import EconParams, PowerMap, load_any_params  # noqa: F401

__all__ = ["EconParams", "PowerMap", "load_any_params"]

warnings.warn("acid.econ has moved to acid.models.econ_params; the old name will be removed "
              "in the next release", MovedWarning, stacklevel=2)
