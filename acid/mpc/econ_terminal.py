"""Moved to :mod:`acid.control.econ.terminal`: this alias warns, and goes in the next
release."""

from acid._compat import alias

alias(__name__)
