"""Moved to :mod:`acid.numbers`: this alias warns, and goes in the next
release."""

from acid._compat import alias

alias(__name__)
