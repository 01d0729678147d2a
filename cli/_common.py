"""What every command shares: one-line errors, progress bars, JSON summaries, tables."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from acid._io import write_json
from acid.errors import AcidError

console = Console()
err_console = Console(stderr=True)


def handle_errors(func: Callable) -> Callable:
    """Turn ``AcidError`` (and a few obvious user mistakes) into one line and exit code 2."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except AcidError as exc:
            err_console.print(f"[bold red]error:[/] {escape(str(exc))}", highlight=False,
                              soft_wrap=True)
            raise typer.Exit(code=exc.exit_code) from None
        except KeyboardInterrupt:
            err_console.print("[bold red]interrupted[/]: nothing half-written was kept")
            raise typer.Exit(code=130) from None

    return wrapper


@contextmanager
def progress_bar(description: str, total: int, enabled: bool = True) -> Iterator[Callable]:
    """A rich progress bar; yields ``update(done, total)`` for library callbacks.

    Disabled (a no-op) when ``enabled`` is False or stderr is not a terminal and CI is set.
    """
    if not enabled:
        yield lambda done, total=None: None
        return
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                  TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn(),
                  TimeRemainingColumn(), console=err_console, transient=False,
                  disable=not sys.stderr.isatty()) as prog:
        task = prog.add_task(description, total=total)

        def update(done: int, total_: int | None = None) -> None:
            prog.update(task, completed=done, total=total_ if total_ is not None else total)

        yield update


def write_summary(path: Path | None, summary: dict) -> None:
    """Write the machine-readable summary when ``--json`` was given."""
    if path is not None:
        write_json(path, summary)
        console.print(f"summary written to {path}")


def print_table(title: str, columns: list[str], rows: list[list], **kwargs) -> None:
    """Print a rich table (cells are converted with ``str``).

    Columns are right-aligned (numbers); a leading ``_`` in a column name asks for a
    left-aligned column and is not shown.
    """
    table = Table(title=title, **kwargs)
    for c in columns:
        left = c.startswith("_")
        table.add_column(c[1:] if left else c, justify="left" if left else "right")
    for r in rows:
        table.add_row(*[str(c) for c in r])
    console.print(table)
