"""Errors that reach the user as one line, and the warning categories acid emits."""

from __future__ import annotations


class AcidError(Exception):
    """A user-facing error: its message is printed as one line and the CLI exits non-zero.

    The message should name the file, channel, key or option at fault. It is kept on one
    line whatever it quotes (a multi-line repr of a bad value, a path with a newline).
    """

    exit_code = 2

    def __init__(self, message: object = "", *args):
        super().__init__(" ".join(str(message).split()), *args)


class DataError(AcidError):
    """A dataset or parameter file is missing, malformed or physically implausible."""


class ConfigError(AcidError):
    """A configuration (plant, excitation, controller, option) is invalid."""


class OutputError(AcidError):
    """An output path cannot be written, or writing it would destroy an input or another
    output of the same command."""


class IdentifiabilityWarning(UserWarning):
    """The data do not excite a parameter (rank deficiency or severe ill-conditioning)."""


class SolverWarning(UserWarning):
    """A numerical solver failed or returned an inaccurate solution; a fallback was used."""


class ExtrapolationWarning(UserWarning):
    """An identified map is evaluated outside the range of the data it was identified on."""


class CodegenWarning(UserWarning):
    """Generated C could not be compiled or loaded; the CasADi solver is used instead."""


class InSampleWarning(UserWarning):
    """A model is validated on (part of) the data it was fitted on."""


class MovedWarning(FutureWarning):
    """An old import path of a module that moved (``acid._compat``): works for one release."""
