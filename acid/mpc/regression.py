"""Moved to :mod:`acid.studies.mpc_check.regression`: this alias warns, and goes in the next
release."""

from acid._compat import alias

alias(__name__)
