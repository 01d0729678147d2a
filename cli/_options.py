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


#: Every option that sizes the work (a duration, a horizon, a count of runs, starts or
#: workers): (command, option) -> (least, most, unit); a sub-command is named with its group
#: ("car select"). A value given on the command line
#: outside it (or not finite) is refused while parsing, in one line naming the option, before
#: any work; ``--help`` states the range. The commands' own checks stay (same or tighter).
SECONDS_WEEK = 7 * 86400.0
WORK_LIMITS: dict[tuple[str, str], tuple[float, float, str]] = {
    ("cav-study", "--identify-duration"): (3600.0, SECONDS_WEEK, "s"),
    ("cav-study", "--horizon"): (2, 200, "steps"),
    ("cav-study", "--econ-horizon"): (10.0, 3600.0, "s"),
    ("cav-study", "--warmup"): (0.0, SECONDS_WEEK, "s"),
    ("cav-study", "--tail"): (0.0, SECONDS_WEEK, "s"),
    ("cav-study", "--jobs"): (1, 256, "processes"),
    ("car control", "--horizon"): (2, 720, "steps"),   # 5 s steps
    ("car select", "--rule-time"): (1.0, SECONDS_WEEK, "s"),
    ("car select", "--warmup"): (0.0, SECONDS_WEEK, "s"),
    ("car select", "--horizon"): (1, 1_000_000, "steps"),
    ("car select", "--starts"): (1, 100_000, "starts"),
    ("car select", "--folds"): (2, 10_000, "folds"),
    ("car select", "--resamples"): (10, 1_000_000, "resamples"),
    ("car select", "--max-evals"): (1, 100_000, "evaluations"),
    ("car select", "--oe-window"): (5, 100_000, "samples"),
    ("car validate", "--folds"): (2, 10_000, "folds"),
    ("compare", "--identify-duration"): (3600.0, SECONDS_WEEK, "s"),
    ("compare", "--jobs"): (1, 256, "processes"),
    ("day", "--days"): (1, 1000, "days"),
    ("day", "--jobs"): (1, 256, "processes"),
    ("excite", "--duration"): (0.0, 30 * 86400.0, "s"),
    ("excite", "--min-dwell"): (0.0, 86400.0, "s"),
    ("excite", "--max-dwell"): (0.0, 86400.0, "s"),
    ("export-c", "--horizon"): (2, 100, "steps"),
    ("export-c", "--check-states"): (1, 10_000, "states"),
    ("fit", "--oe-window"): (5, 100_000, "samples"),
    ("fit", "--max-evals"): (1, 100_000, "evaluations"),
    ("fit", "--fit-starts"): (1, 1000, "starts"),
    ("heating-control", "--horizon"): (2, 600, "steps"),
    ("heating-control", "--warmup"): (0.0, 86400.0, "s"),
    ("heating-control", "--tail"): (0.0, 86400.0, "s"),
    ("heating-control", "--pull-up"): (0.0, 3600.0, "s"),
    ("reproduce", "--jobs"): (1, 256, "processes"),
    ("speed-sweep", "--duration"): (0.0, 86400.0, "s"),
    ("sweep", "--jobs"): (1, 256, "processes"),
    ("validate", "--starts"): (1, 100_000, "starts"),
    ("validate", "--horizon"): (1, 1_000_000, "steps"),
    ("validate", "--warmup"): (0.0, SECONDS_WEEK, "s"),
    ("validate", "--cv-folds"): (2, 100_000, "folds"),
    ("validate", "--resamples"): (10, 1_000_000, "resamples"),
    ("validate", "--max-evals"): (1, 100_000, "evaluations"),
    ("year-sweep", "--jobs"): (1, 256, "processes"),
}


#: Options that size the work by how many things they list (comma-separated in one value, or
#: the option repeated): (command, option) -> (most, what). More is refused while parsing.
LIST_LIMITS: dict[tuple[str, str], tuple[int, str]] = {
    ("compare", "--identify-records"): (100, "records"),
    ("fit", "--add-record"): (100, "records"),
    ("car select", "--candidates"): (20, "structures"),
    ("car select", "--trips"): (1000, "trips"),
    ("car fit", "--held-out"): (1000, "trips"),
}


#: Options that contradict each other when both are given on the command line:
#: command -> pairs. Refused while parsing, naming both.
EXCLUSIVE: dict[str, tuple[tuple[str, str], ...]] = {
    "day": (("--planner", "--no-planner"),),
}


#: Options that mean something only beside another: command -> (option, needed option).
REQUIRES: dict[str, tuple[tuple[str, str], ...]] = {
    "validate": (("--error-model-data", "--error-model"),),
}


def exclusive_error(command: str, given: set[str]) -> str | None:
    """The complaint about two contradicting options both in ``given``, or an option given
    without the one it needs (it would be silently ignored), or None."""
    for a, b in EXCLUSIVE.get(command, ()):
        if a in given and b in given:
            return f"{a} and {b} are both given: give one of them"
    for a, b in REQUIRES.get(command, ()):
        if a in given and b not in given:
            return f"{a} applies only with {b}; without it {a} would be ignored"
    return None


def _count(value) -> int:
    if isinstance(value, str):
        return len([s for s in value.split(",") if s.strip()])
    return len(value)


def _span(lo: float, hi: float, unit: str) -> str:
    return f"{lo:g} to {hi:g}{' ' + unit if unit else ''}"


def limit_help(command: str, flag: str, text: str | None) -> str | None:
    """``text`` (an option's help) with its work limit stated, when it has one."""
    limit = WORK_LIMITS.get((command, flag))
    items = LIST_LIMITS.get((command, flag))
    if (limit is None and items is None) or text is None or "(limit:" in text:
        return text
    text = text.rstrip()
    stop = "." if text.endswith(".") else ""
    span = _span(*limit) if limit is not None else f"at most {items[0]} {items[1]}"
    return f"{text.rstrip('.')} (limit: {span}){stop}"


def work_limit_error(command: str, flag: str, value) -> str | None:
    """Why ``value`` of ``flag`` is outside the command's work limit, or None."""
    import math

    items = LIST_LIMITS.get((command, flag))
    if items is not None and isinstance(value, (str, list, tuple)) and _count(value) > items[0]:
        return (f"{flag}: {_count(value)} {items[1]} given, at most {items[0]} (each one is a "
                "run of its own)")
    limit = WORK_LIMITS.get((command, flag))
    if limit is None or value is None or isinstance(value, bool):
        return None
    values = value if isinstance(value, (list, tuple)) else [value]
    lo, hi, unit = limit
    for v in values:
        if isinstance(v, (int, float)) and not (math.isfinite(v) and lo <= v <= hi):
            return f"{flag} {v!r}: must be in [{lo:g}, {hi:g}]{' ' + unit if unit else ''}"
    return None
