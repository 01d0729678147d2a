"""Moved to :mod:`acid.models.econ_params` (the values) and :mod:`acid.ident.econ` (``identify``);
this alias warns and goes in the next release."""

import warnings

from acid.errors import MovedWarning
from acid.ident.econ import REQUIRED, EconFit, identify  # noqa: F401
from acid.models.econ_params import *  # noqa: F403
from acid.models.econ_params import NAMES, EconParams, PowerMap, load_any_params  # noqa: F401

warnings.warn("acid.econ.params has moved to acid.models.econ_params and acid.ident.econ; the old "
              "name will be removed in the next release", MovedWarning, stacklevel=2)
