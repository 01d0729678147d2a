"""One option name per concept across every command, and the old names kept as hidden aliases.

``CANONICAL`` names the one option every command uses for a concept (the test
``tests/test_cli_options.py`` walks every command's parameters and fails when a command spells
a concept otherwise). ``ALIASES`` maps each retired spelling onto its canonical name: the
commands (``AcidCommand`` in ``cli/main.py``) rewrite it before parsing, so an old command line
keeps working, while ``--help`` shows only the canonical name::

    acid plant-check --config paper --ambient 35   # read as --plant-config paper --t-amb 35
"""

from __future__ import annotations

from collections.abc import Iterable

#: concept -> the one option name for it (every command that takes the concept uses it)
CANONICAL: dict[str, str] = {
    "ambient": "--t-amb",             # degC, like --t-low/--t-high and the channel T_amb
    "ambient range": "--t-amb-range",
    "record design": "--design",      # acid excite: random or soak-and-pull-down segments
    "plant configuration": "--plant-config",  # a TOML file or a vehicle name ('paper')
    "refrigerant": "--refrigerant",
    "FMU map": "--fmu-map",           # read by --plant fmu:..., written by export-fmu
    "parameters": "--params",
    "cycle": "--cycle",
    "seed": "--seed",
    "out": "--out",
    "json": "--json",
    "quick": "--quick",
    "jobs": "--jobs",
}

#: retired spelling -> canonical name (hidden: accepted, never shown in --help)
ALIASES: dict[str, str] = {
    "--ambient": "--t-amb",
    "--config": "--plant-config",
    "--workers": "--jobs",
    "--map": "--fmu-map",             # export-fmu (import's --map is its channel map)
}


def canonical_args(args: Iterable[str], known: set[str]) -> list[str]:
    """``args`` with every retired option name replaced by its canonical one, where the
    command has the canonical option and not the retired one (``known``: the command's option
    names). ``--old=value`` is rewritten too; nothing after ``--`` is touched."""
    out: list[str] = []
    args = list(args)
    for i, arg in enumerate(args):
        if arg == "--":
            return out + args[i:]
        name, sep, value = arg.partition("=")
        new = ALIASES.get(name)
        if new is not None and new in known and name not in known:
            arg = new + sep + value
        out.append(arg)
    return out
