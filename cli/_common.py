"""What every command shares: one-line errors, interrupts, output-path checks, progress bars,
JSON summaries, tables.

Conventions for a command module (see ``ARCHITECTURE.md``):

* decorate the command with ``@handle_errors``;
* call ``check_paths(inputs=..., outputs=..., folders=...)`` first, before any work, with
  every file it reads and writes, labelled by its option (``--out``) or argument (``DATA``);
* check option values with ``require`` / ``require_range`` (one line naming the option);
* print user-derived text (paths, channel names, messages) with ``say`` / ``warn`` / ``note``
  or ``print_table``: they print it literally, never as rich markup.
"""

from __future__ import annotations

import functools
import math
import os
import re
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

import typer
from rich.console import Console, ConsoleDimensions
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Column, Table
from rich.text import Text

from acid._io import check_writable_file, write_json
from acid.errors import AcidError, ConfigError, DataError, OutputError
from acid.units import json_in_degC
from acid_cli._signals import InterruptGuard, raise_if_interrupted

try:  # typer >= 0.2x vendors click
    from typer._click.exceptions import ClickException
except ImportError:  # pragma: no cover - older typer on top of click
    from click.exceptions import ClickException

#: Columns of tables and text when the output is not a terminal (a log, a pipe, CI) and
#: COLUMNS is not set: rich's 80 (or the width of the terminal acid was started from) would
#: cut table cells short ("6.97e-…", "defa…") in the log, and make it depend on that terminal.
LOG_COLUMNS = 120


class _Console(Console):
    """A rich console that renders ``LOG_COLUMNS`` wide into a log (a cut cell is a lost
    number); on a terminal, or with COLUMNS set, as rich does."""

    @property
    def size(self) -> ConsoleDimensions:
        size = Console.size.fget(self)
        if self._width is None and "COLUMNS" not in os.environ and not self.is_terminal:
            return ConsoleDimensions(LOG_COLUMNS, size.height)
        return size

    @size.setter
    def size(self, new_size: tuple[int, int]) -> None:
        Console.size.fset(self, new_size)


console = _Console()
err_console = _Console(stderr=True)

#: Set to show the traceback of an unexpected error (a bug) instead of one line.
DEBUG_ENV = "ACID_DEBUG"


# ----------------------------------------------------------------------------- printing
def one_line(message: object) -> str:
    """``message`` as one line (line breaks become spaces)."""
    return re.sub(r"\s*[\r\n]+\s*", " ", str(message)).strip()


def say(text: object, *, style: str | None = None) -> None:
    """Print ``text`` literally on stdout (no rich markup, no highlighting)."""
    console.print(Text(str(text), style=style or ""), highlight=False)


def _tagged(tag: str, style: str, message: object) -> Text:
    return Text.assemble((tag, style), " ", one_line(message))


def error_line(message: object) -> None:
    """Print ``error: <message>`` as one literal line on stderr."""
    err_console.print(_tagged("error:", "bold red", message), soft_wrap=True, highlight=False)


def warn(message: object) -> None:
    """Print ``warning: <message>`` as one literal line on stderr."""
    err_console.print(_tagged("warning:", "bold yellow", message), soft_wrap=True,
                      highlight=False)


def note(message: object) -> None:
    """Print ``note: <message>`` as one literal line on stdout."""
    console.print(_tagged("note:", "bold", message), soft_wrap=True, highlight=False)


# ------------------------------------------------------------------------------- errors
def handle_errors(func: Callable) -> Callable:
    """Run a command: ``AcidError`` becomes one ``error:`` line and exit 2; Ctrl-C/SIGTERM
    exit 130/143 with nothing partial left; an unexpected exception (a bug) is one line and
    exit 1 (``ACID_DEBUG=1`` shows its traceback)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        def interrupted():
            err_console.print(Text.assemble(("interrupted", "bold red"),
                                            ": stopped, no partial output was kept"),
                              highlight=False)
            return typer.Exit(code=guard.exit_code)

        with InterruptGuard() as guard:
            try:
                kwargs = {k: resolve_examples(v) for k, v in kwargs.items()}
                return func(*args, **kwargs)
            except AcidError as exc:
                if guard.signum is not None:  # what the interrupt left behind, not the cause
                    raise interrupted() from None
                error_line(exc)
                raise typer.Exit(code=exc.exit_code) from None
            except KeyboardInterrupt as exc:
                culprit = _raised_by_user_code(exc, guard)
                if culprit is not None:
                    error_line(f"{culprit}: raises KeyboardInterrupt, yet no interrupt was "
                               "sent (a model file's function?): raise an error there instead")
                    raise typer.Exit(code=2) from None
                raise interrupted() from None
            except (typer.Exit, typer.Abort, ClickException):
                raise
            except MemoryError:
                error_line("out of memory: the requested size is too large for this machine")
                raise typer.Exit(code=2) from None
            except Exception as exc:
                # a KeyboardInterrupt raised inside a C extension's call comes back as some
                # other exception (CasADi's SWIG layer: a NotImplementedError about the
                # arguments); once a signal arrived, the command was interrupted
                if guard.signum is not None:
                    raise interrupted() from None
                if os.environ.get(DEBUG_ENV):
                    raise
                error_line(f"internal error ({exc.__class__.__name__}: {exc}); this is a bug "
                           f"in acid, {DEBUG_ENV}=1 shows the traceback")
                raise typer.Exit(code=1) from None

    return wrapper


def _raised_by_user_code(exc: BaseException, guard: InterruptGuard) -> str | None:
    """``FILE:LINE`` of a user's file (not acid, not an installed package) that raised the
    ``KeyboardInterrupt`` ``exc`` itself, when no SIGINT/SIGTERM reached the command's guard
    (its handlers installed, so a real Ctrl-C would have been recorded); else None."""
    import sysconfig

    if guard.signum is not None or not guard.installed:
        return None
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    if tb is None:
        return None
    path = Path(tb.tb_frame.f_code.co_filename).resolve()
    here = Path(__file__).resolve().parent
    ours = [here, here.parent / "acid", *(Path(sysconfig.get_paths()[k]).resolve()
                                          for k in ("stdlib", "platstdlib", "purelib",
                                                    "platlib"))]
    if not path.is_file() or any(path.is_relative_to(p) for p in ours):
        return None
    return f"{path.name}:{tb.tb_lineno}"


def resolve_examples(value):
    """``example:NAME`` (a path or text option, or a list of them) as the bundled file it
    names (``acid.examples``), the same type kept; anything else unchanged. Every command's
    arguments pass through here (``handle_errors``), so a bundled file is addressable
    wherever a file is read, from any folder."""
    from acid import examples

    if isinstance(value, (list, tuple)):
        return type(value)(resolve_examples(v) for v in value)
    if not examples.is_reference(value):
        return value
    path = examples.resolve(value)
    return path if isinstance(value, Path) else str(path)


def require(condition: bool, option: str, message: str) -> None:
    """Refuse an option value: ``ConfigError("<option> <message>")`` unless ``condition``."""
    if not condition:
        raise ConfigError(f"{option} {message}")


def require_range(value: float, option: str, lo: float | None = None, hi: float | None = None,
                  unit: str = "", *, lo_open: bool = False, integer: bool = False) -> None:
    """Refuse a number outside ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``) or not finite."""
    u = f" {unit}" if unit else ""
    if lo is None:
        span = f"<= {hi:g}{u}"
    elif hi is None:
        span = f"{'>' if lo_open else '>='} {lo:g}{u}"
    else:
        span = f"in {'(' if lo_open else '['}{lo:g}, {hi:g}]{u}"
    ok = isinstance(value, (int, float)) and math.isfinite(value)
    if ok and lo is not None:
        ok = value > lo if lo_open else value >= lo
    if ok and hi is not None:
        ok = value <= hi
    if ok and integer:
        ok = float(value).is_integer()
    require(ok, option, f"must be {'an integer ' if integer else ''}{span}, got {value!r}")


# --------------------------------------------------------------------------- file paths
PathLike = str | os.PathLike


def _same(a: Path, b: Path) -> bool:
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def check_paths(*, inputs: Mapping[str, PathLike | None] | None = None,
                outputs: Mapping[str, PathLike | None] | None = None,
                folders: Mapping[str, tuple[PathLike | None, Iterable[str]]] | None = None,
                read_folders: Mapping[str, PathLike | None] | None = None,
                records: Iterable[str] = ()) -> None:
    """Check a command's files before any work; one line naming the option on a problem.

    Parameters
    ----------
    inputs : {label: path} files the command reads (``None`` values are skipped): each must
        exist and be a file.
    outputs : {label: path} files the command writes: none may be a folder, sit under a file,
        or lie in a folder this process cannot write.
    folders : {label: (folder, names)} folders the command writes the files ``names`` into.
    read_folders : {label: folder} folders whose files the command reads (a folder of logs):
        no output may lie inside one (it would replace a log, or be read as one next time).
    records : labels of ``inputs`` each read as an experiment of its own: no two may be the
        same file (the same data twice would count twice).

    No output may be an input (the same file by any path: links, ``..``, symlinks), and no
    two outputs may be the same file. Labels are the option or argument names the user typed
    (``--out``, ``--json``, ``DATA``) and appear in the messages.
    """
    ins = [(k, Path(v)) for k, v in (inputs or {}).items() if v is not None]
    outs = [(k, Path(v)) for k, v in (outputs or {}).items() if v is not None]
    dirs = [(k, Path(v), tuple(names)) for k, (v, names) in (folders or {}).items()
            if v is not None]

    for label, p in ins:
        if not p.exists():
            raise DataError(f"{label} {p}: file not found")
        if p.is_dir():
            raise DataError(f"{label} {p}: is a folder, expected a file")

    recs = [(k, p) for k, p in ins if k in set(records)]
    for i, (label, p) in enumerate(recs):
        for other, q in recs[:i]:
            if _same(p, q):
                raise DataError(f"{label} {p}: is the same file as {other}; each is read "
                                "as data of its own (the same file twice would count twice, "
                                "or held-out data would be fitted on)")

    written: list[tuple[str, Path]] = list(outs)
    for label, d, names in dirs:
        if str(d) == "":
            raise OutputError(f"{label}: an output folder needs a name")
        if d.exists() and not d.is_dir():
            raise OutputError(f"{label} {d}: is a file, expected a folder")
        _check_folder_writable(label, d)
        written.extend((label, d / n) for n in names)

    for label, p in written:
        if _bundled(p):
            raise OutputError(f"{label} {p}: is a file bundled with acid; write elsewhere "
                              "(`acid examples copy NAME` copies one to edit)")
        try:
            check_writable_file(p)
        except OutputError as exc:
            raise OutputError(f"{label} {exc}") from None
        for in_label, d in (read_folders or {}).items():
            if d is not None and _inside(p, Path(d)):
                raise OutputError(f"{label} {p}: is inside the folder {in_label} ({d}) the "
                                  "command reads; write elsewhere")
        for in_label, q in ins:
            if _same(p, q):
                raise OutputError(f"{label} {p}: is also the input {in_label} ({q}); refusing "
                                  "to overwrite it")
    for i, (label, p) in enumerate(written):
        for other, q in written[:i]:
            if _same(p, q):
                by = "twice" if other == label else f"also by {other} ({q})"
                raise OutputError(f"{label} {p}: would be written {by}; give each output "
                                  "its own path")


def _inside(p: Path, folder: Path) -> bool:
    """Whether ``p`` (resolved: links, ``..``) lies anywhere below ``folder``."""
    try:
        return p.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError):
        return False


def _bundled(p: Path) -> bool:
    from acid.examples import is_bundled

    return is_bundled(p)


def _check_folder_writable(label: str, d: Path) -> None:
    probe = d
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise OutputError(f"{label} {d}: cannot create it, {probe} is a file, not a folder")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise OutputError(f"{label} {d}: folder {probe} is not writable")


def plant_inputs(plant: str | None, fmu_map: PathLike | None) -> dict[str, PathLike | None]:
    """The files behind ``--plant fmu:PATH.fmu`` and ``--fmu-map`` (for ``check_paths``)."""
    fmu = plant[len("fmu:"):] if plant and plant.startswith("fmu:") else None
    return {"--plant": fmu or None, "--fmu-map": fmu_map}


def params_input(spec: str | None) -> str | None:
    """The file behind a ``--params``/``--reference`` value (``None`` for the 'paper' preset)."""
    return None if spec is None or str(spec) == "paper" else spec


# ------------------------------------------------------------------------ progress, io
#: When stderr is not a terminal, a progress line at least this often while the work moves, s.
PLAIN_EVERY_S = 30.0


def progress_is_plain() -> bool:
    """Whether progress goes out as plain lines (stderr is a log, a pipe or CI: no terminal
    to redraw a bar on)."""
    return not err_console.is_terminal


class ProgressLines:
    """Progress as plain lines on stderr, for logs (``| tee``, CI), where a redrawn bar is
    swallowed: ``description: done/total (pct %), elapsed s[: label]``, one line each tenth of
    the work, at the end, and at least every ``PLAIN_EVERY_S`` while the count moves.

    Call it as ``update(done, total=None, label=None)``; ``label`` names what just finished
    (a cycle, a controller, a scenario)."""

    def __init__(self, description: str, total: int | None):
        self.description, self.total = description, total
        self._t0 = self._last_t = time.monotonic()
        self._last_done, self._last_tenth = None, -1

    def __call__(self, done: int, total: int | None = None, label: str | None = None) -> None:
        raise_if_interrupted()   # a Ctrl-C the library swallowed stops at its next report
        if total is not None:
            self.total = total
        if done == self._last_done:
            return
        now = time.monotonic()
        tenth = int(10 * done / self.total) if self.total else -1
        if (label is None and tenth <= self._last_tenth and now - self._last_t < PLAIN_EVERY_S
                and not (self.total and done >= self.total)):
            return
        self._last_done, self._last_tenth, self._last_t = done, tenth, now
        self.line(f"{done}/{self.total} ({100 * done / self.total:.0f} %)" if self.total
                  else f"{done}", label, now)

    def line(self, text: str, label: str | None = None, now: float | None = None) -> None:
        """One line ``description: text, elapsed s[: label]`` on stderr."""
        elapsed = (time.monotonic() if now is None else now) - self._t0
        err_console.print(Text(f"{self.description}: {text}, {elapsed:.0f} s"
                               + (f": {label}" if label else "")),
                          soft_wrap=True, highlight=False)


@contextmanager
def progress_bar(description: str, total: int | None,
                 enabled: bool = True) -> Iterator[Callable]:
    """Progress of a long run; yields ``update(done, total=None, label=None)`` for library
    callbacks.

    A rich bar on a terminal, with the last ``label`` after it (literally: user text);
    plain lines (``ProgressLines``) when stderr is not one (a log, ``| tee``, CI); a no-op
    when ``enabled`` is False.
    """
    if not enabled:
        yield lambda done, total=None, label=None: None
        return
    if progress_is_plain():
        yield ProgressLines(description, total)   # its first line at the first update
        return
    last = TextColumn("{task.fields[label]}", markup=False,   # the bar keeps its room
                      table_column=Column(no_wrap=True, overflow="ellipsis",
                                          max_width=max(16, err_console.width // 3)))
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                  MofNCompleteColumn(), TimeElapsedColumn(),   # "0/?" until a total is known
                  TimeRemainingColumn(), last, console=err_console, transient=False) as prog:
        task = prog.add_task(escape(description), total=total, label="")

        def update(done: int, total_: int | None = None, label: str | None = None) -> None:
            raise_if_interrupted()
            prog.update(task, completed=done, total=total_ if total_ is not None else total,
                        **({"label": one_line(label)} if label else {}))

        yield update


def chained_steps(update: Callable, after: int) -> tuple[Callable, Callable[[str], None]]:
    """One progress (``update`` of ``progress_bar``) over a library's steps, then ``after``
    steps of the command's own: ``(library, step)``, ``library(done, total, label)`` the
    library's callback (its total learnt from its calls), ``step(label)`` after each of the
    command's steps."""
    count = {"done": 0, "total": after}

    def library(done: int, total: int, label: str | None = None) -> None:
        count["done"], count["total"] = done, total + after
        update(done, count["total"], label)

    def step(label: str) -> None:
        count["done"] += 1
        update(count["done"], count["total"], label)

    return library, step


def timed_lines(description: str) -> Callable[[str], None]:
    """``say(message)`` for a library's progress messages, each line with the time since this
    call (``description: message, 12 s``), on stderr."""
    lines = ProgressLines(description, None)
    return lines.line


def write_summary(path: Path | None, summary: dict) -> None:
    """Write the machine-readable summary when ``--json`` was given (absolute temperatures
    in degC, ``acid.units.json_in_degC``)."""
    if path is not None:
        write_json(path, json_in_degC(summary))
        say(f"summary written to {path}")


def print_table(title: str, columns: list[str], rows: list[list], **kwargs) -> None:
    """Print a rich table (cells are converted with ``str`` and shown literally).

    Columns are right-aligned (numbers); a leading ``_`` in a column name asks for a
    left-aligned column and is not shown.
    """
    table = Table(title=Text(str(title), style="table.title"), **kwargs)
    for c in columns:
        left = c.startswith("_")
        table.add_column(c[1:] if left else c, justify="left" if left else "right")
    for r in rows:
        table.add_row(*[Text(str(c)) for c in r])
    console.print(table)
