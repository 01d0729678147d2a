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


def repeated_options(args: Iterable[str], params) -> str | None:
    """The complaint about an option given more than once with different values in
    ``args`` (after ``canonical_args``), or None. ``params``: the command's click parameters.
    A repeatable option (``multiple``: ``--input``, ``--t-amb`` of some commands) may repeat,
    the command judges its values; any other keeps one value, so ``--horizon 5 --horizon 7``
    (which would silently run with 7) is refused, as is a flag given with its negation
    (``--check --no-check``). The same value twice is harmless and accepted."""
    owner: dict[str, tuple[object, str | None]] = {}   # spelling -> (param, flag value)
    for p in params:
        if getattr(p, "param_type_name", "") != "option" or getattr(p, "multiple", False):
            continue
        for o in p.opts:
            owner[o] = (p, "on" if getattr(p, "is_flag", False) else None)
        for o in getattr(p, "secondary_opts", ()):
            owner[o] = (p, "off")
    seen: dict[object, tuple[str, str]] = {}   # param -> (spelling, value)
    args = list(args)
    if "--help" in args:
        return None
    i = 0
    while i < len(args):
        arg = args[i]
        if arg == "--":
            break
        name, sep, value = arg.partition("=")
        hit = owner.get(name)
        i += 1
        if hit is None:
            continue
        p, flag = hit
        if flag is not None:
            value = flag
        elif not sep:
            n = max(1, p.nargs)
            value = " ".join(args[i:i + n])
            i += n
        before = seen.get(p)
        if before is not None and before[1] != value:
            if flag is not None:
                return f"{before[0]} and {name} are both given: give one of them"
            return (f"{name} is given twice ({before[1]!r} and {value!r}): give it once "
                    "(only options that take several values repeat)")
        seen[p] = (name, value)
    return None
