"""One option name per concept across every command (issue 23), the retired names still
accepted (hidden), and what every plant-driving command takes."""

from __future__ import annotations

import re
import typing

import pytest
import typer
from typer.testing import CliRunner

from acid_cli._options import ALIASES, CANONICAL, canonical_args
from acid_cli.main import app

runner = CliRunner()

#: how a concept may be spelled (any visible option matching the pattern is that concept) and
#: the names allowed for it: the canonical one, plus options that are another concept on purpose
SPELLINGS: dict[str, tuple[str, set[str]]] = {
    "ambient": (r"amb", {CANONICAL["ambient"], CANONICAL["ambient range"]}),
    "plant configuration": (r"config|vehicle|\bcar\b", {CANONICAL["plant configuration"]}),
    "refrigerant": (r"refrig|fluid|r134|r1234", {CANONICAL["refrigerant"]}),
    "FMU map": (r"fmu", {CANONICAL["FMU map"]}),
    # --econ-params: the econ model's parameters beside the paper model's (cav-study takes both)
    "parameters": (r"param", {CANONICAL["parameters"], "--econ-params"}),
    "cycle": (r"cycle|drive", {CANONICAL["cycle"]}),
    "seed": (r"seed|random|rng", {CANONICAL["seed"]}),
    "out": (r"^--out|output|^--dest", {CANONICAL["out"]}),
    "json": (r"json", {CANONICAL["json"]}),
    "quick": (r"quick|fast|short", {CANONICAL["quick"]}),
    "jobs": (r"jobs|worker|process|thread|parallel|cores", {CANONICAL["jobs"]}),
}


def _commands() -> dict:
    """Every sub-command (Typer's vendored Click ``Command`` objects), by name."""
    commands = dict(typer.main.get_command(app).commands)
    assert len(commands) > 10, "the sub-commands did not register"
    return commands


def _options(cmd) -> list:
    """The visible options of ``cmd`` (not its arguments)."""
    return [p for p in cmd.params if p.param_type_name == "option" and not p.hidden]


def _long_names(p) -> list[str]:
    return [n for n in (*p.opts, *p.secondary_opts) if n.startswith("--")]


def test_every_concept_has_one_name_across_commands():
    wrong = []
    for cmd_name, cmd in _commands().items():
        for p in _options(cmd):
            for name in _long_names(p):
                bare = re.sub(r"^--(no-)?", "--", name)
                for concept, (pattern, allowed) in SPELLINGS.items():
                    if re.search(pattern, bare) and bare not in allowed:
                        wrong.append(f"acid {cmd_name} {name}: the {concept} is "
                                     f"{' or '.join(sorted(allowed))} in acid")
    assert not wrong, "\n".join(wrong)


def test_one_python_name_is_one_option_name():
    """A parameter's name in the code (``out``, ``plant_config``) is spelled one way on every
    command's command line."""
    seen: dict[str, dict[str, str]] = {}
    for cmd_name, cmd in _commands().items():
        for p in _options(cmd):
            seen.setdefault(p.name, {})[cmd_name] = "/".join(_long_names(p))
    split = {name: by for name, by in seen.items() if len(set(by.values())) > 1}
    assert not split, split


def test_the_canonical_names_are_used():
    used = {n for cmd in _commands().values() for p in _options(cmd) for n in _long_names(p)}
    for concept, name in CANONICAL.items():
        assert name in used, f"{concept}: {name} is no command's option"


@pytest.mark.parametrize("old", sorted(ALIASES))
def test_a_retired_name_means_the_canonical_one_and_is_hidden(old):
    new = ALIASES[old]
    takers = {n: c for n, c in _commands().items()
              if any(new in _long_names(p) for p in _options(c))}
    assert takers, f"no command takes {new}"
    for cmd_name, cmd in takers.items():
        param = next(p for p in _options(cmd) if new in _long_names(p))
        value = "2"  # a number, a path or a name alike
        ctx_new = cmd.make_context(cmd_name, _minimal_args(cmd) + [new, value],
                                   resilient_parsing=True)
        ctx_old = cmd.make_context(cmd_name, _minimal_args(cmd) + [old, value],
                                   resilient_parsing=True)
        assert ctx_old.params[param.name] == ctx_new.params[param.name] is not None
        eq = cmd.make_context(cmd_name, _minimal_args(cmd) + [f"{old}={value}"],
                              resilient_parsing=True)
        assert eq.params[param.name] == ctx_new.params[param.name]
        help_text = runner.invoke(app, [cmd_name, "--help"], terminal_width=200).output
        assert new in help_text and not re.search(re.escape(old) + r"\b(?!-)", help_text), (
            f"acid {cmd_name} --help shows {old}")


def _minimal_args(cmd) -> list[str]:
    """Placeholders for the required arguments of ``cmd``."""
    return ["x" for p in cmd.params if p.param_type_name == "argument" and p.required]


def test_rewriting_leaves_other_options_and_the_end_of_options_alone():
    known = {"--plant-config", "--t-amb", "--out"}
    assert canonical_args(["--config", "a", "--ambient=3", "--", "--config"], known) == [
        "--plant-config", "a", "--t-amb=3", "--", "--config"]
    # a command with an option of the old name of its own keeps it
    assert canonical_args(["--config", "a"], {"--config", "--plant-config"}) == ["--config", "a"]
    # a command without the canonical option: the old name stays (and is refused as unknown)
    assert canonical_args(["--workers", "2"], {"--out"}) == ["--workers", "2"]


def test_a_retired_name_on_a_command_without_the_concept_is_refused():
    result = runner.invoke(app, ["claims", "--config", "paper"])
    assert result.exit_code == 2 and "--config" in result.output


def test_every_plant_driving_command_takes_the_ambient():
    for cmd_name, cmd in _commands().items():
        names = {n for p in _options(cmd) for n in _long_names(p)}
        if "--plant" in names:
            assert CANONICAL["ambient"] in names, f"acid {cmd_name} has --plant, no --t-amb"
        if CANONICAL["plant configuration"] in names:
            assert CANONICAL["refrigerant"] in names, (
                f"acid {cmd_name} takes --plant-config but no --refrigerant")


#: what an option's help text says it counts or measures: one kind per option name across
#: commands (the first unit the help names: "steps of 5 s" is a count, "s (whole samples)" a
#: time)
UNIT_KINDS: dict[str, str] = {
    "count": r"\b(samples?|steps?)\b",
    "time": r"(?<![\w'])(s|seconds?|min|minutes?|h|hours?)(?=[\s.,;:)]|$)",
    "temperature": r"degC|°C|(?<![\w'])K(?=[\s.,;:)]|$)",
}


def unit_kind(help_text: str) -> str | None:
    """The kind of quantity ``help_text`` states first (None: none stated)."""
    found = {kind: m.start() for kind, pattern in UNIT_KINDS.items()
             if (m := re.search(pattern, help_text))}
    return min(found, key=found.get) if found else None


def test_unit_kind_reads_help_texts():
    assert unit_kind("Warm-up before the cycle, s.") == "time"
    assert unit_kind("samples before each start") == "count"
    assert unit_kind("the stretch before each start, s (whole samples of Ts)") == "time"
    assert unit_kind("Prediction steps per start (300 x 5 s = 1500 s).") == "count"
    assert unit_kind("Ambient temperature, degC (default: the plant's).") == "temperature"
    assert unit_kind("the plant's configuration") is None


def _is_number(p) -> bool:
    """Whether option ``p`` takes a number (``float``, ``int``, or either or None)."""
    annotation = p.type_descriptor.annotation
    return bool({int, float} & {annotation, *typing.get_args(annotation)})


def test_one_option_name_has_one_unit_across_commands():
    """``--warmup`` in samples on one command and in seconds on another is one name for two
    things: every number option that several commands share states one kind of unit."""
    kinds: dict[str, dict[str, str]] = {}
    for cmd_name, cmd in _commands().items():
        for p in _options(cmd):
            if not _is_number(p):
                continue
            kind = unit_kind(" ".join((p.help or "").split()))
            if kind is not None:
                kinds.setdefault(_long_names(p)[0], {})[cmd_name] = kind
    mixed = {name: by for name, by in kinds.items() if len(set(by.values())) > 1}
    assert not mixed, mixed
    assert set(kinds["--warmup"].values()) == {"time"}
