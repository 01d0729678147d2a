"""Moved to :mod:`acid.ident.analysis`: this alias warns, and goes in the next
release."""

from acid._compat import alias

alias(__name__)
