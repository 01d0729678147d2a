"""A generated hostile-input scan: every numeric option of every command (read from the Typer
app, so new options are covered without a hand list) given NaN, +-inf, a negative number,
zero and 1e300; every temperature option below absolute zero; every range option reversed;
plus the hand-written cases of ``_catalogue.py``. Run as a script for a before/after count:

    python tests/_hostile.py [--budget SECONDS] [--only COMMAND]

Each case runs in-process (``CliRunner``) from inside a copy of the catalogue's workspace
(so default output folders land there), with a wall-clock budget (SIGALRM): a command that
accepts the value and starts working is stopped at the budget and counted ``running``.

Verdicts: ``clean`` (exit 2, one ``error:`` line naming the option), ``accepted`` (exit 0 or
still running at the budget: fine for a plausible value, a finding for a nonsense one:
NaN, inf, 1e300, below absolute zero, a reversed range), ``traceback``, ``internal``
(acid's internal-error net), ``unclear`` (several lines, the option not named, another
exit code, a file of the workspace changed).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import sys
import tempfile
import time
import typing
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

#: values every numeric option must refuse (no option has a meaning for them)
NONSENSE = ("nan", "inf", "-inf", "1e300")
#: values an option may accept (a finding only if the command then fails badly)
PLAUSIBLE = ("-1", "0")
#: a temperature below absolute zero, degC
BELOW_ZERO_K = "-300"

D = "{w}/d.h5"
#: the arguments that bring each command to its option checks (outputs inside the workspace)
BASE: dict[str, tuple[str, ...]] = {
    "fit": ("fit", D, "--out", "{w}/q.json"),
    "validate": ("validate", D, "--out", "{w}/figs", "--starts", "5", "--horizon", "50"),
    "import": ("import", "{w}/run.csv", "--map", "{w}/map.toml", "--out", "{w}/run.h5"),
    "excite": ("excite", "--plant", "model", "--duration", "600", "--out", "{w}/x.h5"),
    "sweep": ("sweep", "{w}/s.toml", "--out", "{w}/o"),
    "claims": ("claims", "{w}/prev.json"),
    "examples": ("examples",),
    "car": ("car",),
    "heating-check": ("heating-check",),
    "export-fmu": ("export-fmu", "--out", "{w}/p.fmu"),
    "pulldown": ("pulldown", "--quick"),
    # the car study on a copy of the real i3 logs (skipped without them)
    "car fit": ("car", "fit", "{w}/logs", "--out", "{w}/ca.json"),
    "car select": ("car", "select", "{w}/logs"),
    "car validate": ("car", "validate", "{w}/logs"),
    "car control": ("car", "control", "{w}/logs", "--trip", "TripA01"),
}
TEMPERATURE = ("--t-amb", "--t-low", "--t-high", "--switch-over")
RANGES = {"--t-amb-range": ("35", "20"), "--speed-range": ("80", "10")}


@dataclass(frozen=True)
class Probe:
    command: str
    flag: str
    value: str
    nonsense: bool
    args: tuple[str, ...]
    names: tuple[str, ...] = ()   # what the error line must name (default: the flag)
    group: str = "value"          # value, twice, file<slot>, out, kept

    @property
    def id(self) -> str:
        return f"{self.command} {self.flag} {self.value}"


def _numeric(annotation) -> type | None:
    if annotation in (float, int):
        return annotation
    for arg in typing.get_args(annotation):
        kind = _numeric(arg)
        if kind is not None:
            return kind
    return None


def _commands(group=None, prefix: str = "") -> list[tuple[str, object]]:
    """(name, click command) of every command, sub-commands of a group too ("car select")."""
    import typer

    from acid_cli.main import app

    group = group if group is not None else typer.main.get_command(app)
    out = []
    for name, cmd in sorted(group.commands.items()):
        if hasattr(cmd, "commands"):
            out.extend(_commands(cmd, f"{prefix}{name} "))
        else:
            out.append((f"{prefix}{name}", cmd))
    return out


def numeric_options() -> list[tuple[str, str, str, type, int]]:
    """(command, parameter name, flag, float|int, nargs) of every numeric option."""


    out = []
    for name, cmd in _commands():
        for p in getattr(cmd, "params", ()):
            desc = getattr(p, "type_descriptor", None)
            kind = _numeric(getattr(desc, "annotation", None))
            if kind is not None and p.opts and p.opts[0].startswith("--") \
                    and not getattr(p, "is_flag", False):
                # a repeatable option: nargs 0 here (not probed twice)
                out.append((name, p.name, p.opts[0], kind,
                            0 if getattr(p, "multiple", False) else max(1, p.nargs)))
    return out


def probes() -> list[Probe]:
    out = []
    for command, _name, flag, _kind, nargs in numeric_options():
        base = BASE.get(command, (*command.split(), "--out", "{w}/o"))
        values = [(v, True) for v in NONSENSE] + [(v, False) for v in PLAUSIBLE]
        if flag in TEMPERATURE:
            values.append((BELOW_ZERO_K, True))
        for value, nonsense in values:
            out.append(Probe(command, flag, value, nonsense,
                             (*base, flag, *([value] * max(1, nargs)))))
        if flag in RANGES:
            out.append(Probe(command, flag, "reversed", True, (*base, flag, *RANGES[flag])))
        if nargs == 1:   # given twice with different values
            out.append(Probe(command, flag, "twice", True, (*base, flag, "1", flag, "2"),
                             group="twice"))
    return out + file_probes()


#: bad files: (name in the workspace, how to make it from the workspace template)
BAD_FILES = ("empty", "trunc.h5", "trunc.csv", "adir", "nope.h5", "afile")
#: (command, arguments with {f} where the bad file goes)
FILE_SLOTS = (
    ("fit", ("fit", "{f}", "--out", "{w}/q.json")),
    ("validate", ("validate", "{f}", "--out", "{w}/figs")),
    ("import", ("import", "{f}", "--map", "{w}/map.toml", "--out", "{w}/run.h5")),
    ("import", ("import", "{w}/run.csv", "--map", "{f}", "--out", "{w}/run.h5")),
    ("sweep", ("sweep", "{f}", "--out", "{w}/o")),
    ("claims", ("claims", "{f}")),
    ("fit", ("fit", D, "--out", "{w}/q.json", "--reference", "{f}")),
    ("validate", ("validate", D, "--out", "{w}/figs", "--params", "{f}")),
    ("excite", ("excite", "--plant", "model", "--out", "{w}/x.h5", "--params", "{f}")),
    ("excite", ("excite", "--out", "{w}/x.h5", "--plant-config", "{f}")),
    ("mpc-check", ("mpc-check", "--out", "{w}/mc", "--params", "{f}")),
    ("export-c", ("export-c", "--out", "{w}/ec", "--params", "{f}")),
    ("export-c", ("export-c", "--out", "{w}/ec", "--model", "{f}")),
    ("fit", ("fit", D, "--out", "{w}/q.json", "--model", "{f}")),
    ("speed-sweep", ("speed-sweep", "--out", "{w}/ss", "--plant-config", "{f}")),
    ("year-sweep", ("year-sweep", "--out", "{w}/ys", "--plant-config", "{f}")),
    ("heating-check", ("heating-check", "--logs", "{f}")),
    ("cav-study", ("cav-study", "--out", "{w}/cs", "--params", "{f}")),
    ("plant-check", ("plant-check", "--out", "{w}/pc", "--plant-config", "{f}")),
)
#: outputs that cannot be written, and an earlier output a failing run must keep
OUT_SLOTS = (("{w}/afile/sub", "afile"), ("{w}/adir", "adir"))


def make_bad_files(w: Path) -> None:
    (w / "empty").write_bytes(b"")
    (w / "trunc.h5").write_bytes((w / "d.h5").read_bytes()[:2048])
    (w / "trunc.csv").write_text((w / "run.csv").read_text()[:300])


def file_probes() -> list[Probe]:
    out = []
    for k, (command, args) in enumerate(FILE_SLOTS):
        slot = next(a for a in args if "{f}" in a)
        i = args.index(slot)
        flag = args[i - 1] if args[i - 1].startswith("--") else "ARG"
        for bad in BAD_FILES:
            if bad == "afile" and flag == "--model":
                continue
            f = f"{{w}}/{bad}"
            if flag == "--model" and bad in ("empty", "adir"):
                f += ".py" if bad == "empty" else ""
            out.append(Probe(command, flag, bad, True,
                             tuple(a.replace("{f}", f) for a in args),
                             names=(Path(f).name,), group=f"file{k}"))
    for command, _name, flag, _kind, _n in numeric_options():
        base = BASE.get(command, (*command.split(), "--out", "{w}/o"))
        has_json = any(o == "--json" for o in _flags(command))
        for target, culprit in OUT_SLOTS:
            opt = "--json" if has_json else "--out"
            out.append(Probe(command, opt, culprit, True, (*base, opt, target),
                             names=(culprit,), group="out"))
        if has_json:   # an earlier output kept by a run refused for a nonsense value
            out.append(Probe(command, flag, "nan+json", True,
                             (*base, "--json", "{w}/prev.json", flag, "nan"), group="kept"))
    return _unique(out)


def _flags(command: str) -> list[str]:
    cmd = dict(_commands())[command]
    return [o for p in getattr(cmd, "params", ()) for o in p.opts]


def _unique(probes: list[Probe]) -> list[Probe]:
    seen, out = set(), []
    for p in probes:
        if p.args not in seen:
            seen.add(p.args)
            out.append(p)
    return out


class _Budget(BaseException):
    """The wall-clock budget of one case ran out (BaseException: no ``except Exception``
    of the command swallows it)."""


@contextlib.contextmanager
def budget(seconds: float):
    def ring(*_):
        raise _Budget

    def hung():   # the alarm never reached Python (a long C call, or swallowed): say so
        print(f"hung: still running {10 * seconds:g} s after the budget; stopping the scan",
              flush=True)
        os._exit(3)

    import threading

    watchdog = threading.Timer(10 * seconds, hung)
    watchdog.daemon = True
    old = signal.signal(signal.SIGALRM, ring)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    watchdog.start()
    try:
        yield
    finally:
        watchdog.cancel()
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def run_probe(p: Probe, template: Path, w: Path, seconds: float) -> tuple[str, str, float]:
    """(verdict, output, seconds) of one probe."""
    from _catalogue import snapshot
    from typer.testing import CliRunner

    from acid_cli.main import app

    if w.exists():
        shutil.rmtree(w)
    shutil.copytree(template, w, symlinks=True)
    (w / "s.toml").write_text("[grid]\nambient_C = [30.0]\n")
    make_bad_files(w)
    if any("{w}/logs" in a for a in p.args):
        from _catalogue import REAL_I3, _logs

        if not REAL_I3.is_dir():
            return "skipped", f"{REAL_I3} absent", 0.0
        _logs(w)
    before = snapshot(w)
    here = os.getcwd()
    os.chdir(w)
    t0 = time.monotonic()
    try:
        with budget(seconds):
            res = CliRunner().invoke(app, [a.replace("{w}", str(w)) for a in p.args],
                                     catch_exceptions=True)
    except _Budget:
        return "accepted", "(running at the budget)", time.monotonic() - t0
    finally:
        os.chdir(here)
    took = time.monotonic() - t0
    if isinstance(res.exception, _Budget) or took >= seconds:
        # the budget's signal inside a C extension (CasADi) comes back as another exception
        return "accepted", "(running at the budget)", took
    after = snapshot(w)
    changed = [k for k, v in before.items() if after.get(k) != v]
    out = res.output
    lines = [ln for ln in out.splitlines() if ln.strip()]
    if changed:
        return "unclear", f"changed {changed}", took
    if "Traceback" in out or (res.exception is not None
                              and not isinstance(res.exception, SystemExit)):
        return "traceback", f"{type(res.exception).__name__}: {res.exception}", took
    if res.exit_code == 0:
        return "accepted", out[-200:], took
    flat = " ".join(out.split())
    if "internal error" in flat:
        return "internal", flat[:300], took
    if res.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error:") \
            and all(n in flat for n in (p.names or (p.flag,))):
        return "clean", flat, took
    return "unclear", f"exit {res.exit_code}: {flat[:300]}", took


def main(argv: list[str]) -> int:
    from _catalogue import build_workspace

    seconds = float(argv[argv.index("--budget") + 1]) if "--budget" in argv else 4.0
    only = argv[argv.index("--only") + 1] if "--only" in argv else None
    root = Path(tempfile.mkdtemp(prefix="acid-hostile-"))
    template = build_workspace(root / "template")
    counts: Counter = Counter()
    for p in probes():
        if only and p.command != only:
            continue
        verdict, out, took = run_probe(p, template, root / "case", seconds)
        key = verdict if verdict != "accepted" else ("NONSENSE-accepted" if p.nonsense
                                                     else "accepted")
        counts[key] += 1
        if sum(counts.values()) % 50 == 0:   # a running count (a long scan on a busy machine)
            print(f"... {sum(counts.values())} probes: "
                  + ", ".join(f"{k} {v}" for k, v in counts.most_common()), flush=True)
        if key != "clean":
            print(f"{key:18s} {took:5.1f}s {p.id}: {out.splitlines()[0] if out else ''}"[:220],
                  flush=True)
    total = sum(counts.values())
    print(f"{total} probes: " + ", ".join(f"{k} {v}" for k, v in counts.most_common()))
    shutil.rmtree(root, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    raise SystemExit(main(sys.argv[1:]))
