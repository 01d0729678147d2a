"""The ``acid`` console script: one sub-command per module of ``acid_cli``."""

from __future__ import annotations

import typer

from acid import __version__

app = typer.Typer(
    name="acid",
    help="A/C system identification, model validation and predictive climate control "
         "of electrified vehicles (reproduces Wang et al., ACC 2018).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode="markdown",
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"acid {__version__}")
        raise typer.Exit()


@app.callback()
def main(version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                      help="Print the version and exit.")) -> None:
    """acid: identify, validate and control vehicle A/C systems."""


# Sub-commands register themselves here, one line each (keep this list sorted by pipeline).
from acid_cli import commands  # noqa: E402,F401  (registers the sub-commands on ``app``)
