"""The ``acid`` console script: one sub-command per module of ``acid_cli``."""

from __future__ import annotations

from acid_cli import _signals

_signals.begin_startup()  # Ctrl-C or SIGTERM while the modules below import: exit quietly

import os  # noqa: E402
import sys  # noqa: E402

# multiprocessing's resource tracker (a child of every run that starts local Dask processes)
# reads this when it starts: after a signal has ended the run and its workers, it would warn on
# its way out about the semaphores of the killed workers (noise after the one-line exit).
os.environ["PYTHONWARNINGS"] = ",".join(
    w for w in (os.environ.get("PYTHONWARNINGS"), "ignore:resource_tracker:UserWarning") if w)

import typer  # noqa: E402
from typer.core import TyperCommand, TyperGroup  # noqa: E402

from acid import __version__  # noqa: E402
from acid._blas import fix_process  # noqa: E402
from acid_cli._common import ClickException, error_line  # noqa: E402
from acid_cli._options import (  # noqa: E402
    canonical_args,
    exclusive_error,
    limit_help,
    repeated_options,
    work_limit_error,
)

try:  # typer >= 0.2x vendors click
    from typer._click.core import ParameterSource
    from typer._click.exceptions import UsageError
except ImportError:  # pragma: no cover - older typer on top of click
    from click.core import ParameterSource
    from click.exceptions import UsageError


class FlagsTakeNoValue:
    """Help without a value type after a flag: typer 0.29's rich help writes ``<bool>`` after
    every flag (``--quick <bool>``, ``--help <bool>``) as if it took a value. A flag's empty
    metavar is its type column (typer shows the metavar there when one is set); its plain
    help and parsing never read it. Mixed into every command and the group (``--version``)."""

    def get_params(self, ctx):
        params = super().get_params(ctx)
        for p in params:
            if getattr(p, "is_flag", False) and p.metavar is None:
                p.metavar = ""
        return params


class AcidCommand(FlagsTakeNoValue, TyperCommand):
    """A command that also accepts the retired option names of ``acid_cli._options.ALIASES``
    (hidden: rewritten to their canonical names before parsing, absent from ``--help``)."""

    def parse_args(self, ctx, args):
        known = {name for p in self.params for name in (*p.opts, *p.secondary_opts)}
        args = canonical_args(args, known)
        twice = None if ctx.resilient_parsing else repeated_options(args, self.params)
        if twice is not None:
            raise UsageError(twice, ctx=ctx)
        rest = super().parse_args(ctx, args)
        if not ctx.resilient_parsing:
            given = {o for p in self.params if p.opts
                     and ctx.get_parameter_source(p.name) == ParameterSource.COMMANDLINE
                     for o in _spelled(p, ctx.params.get(p.name))}
            clash = exclusive_error(_path(ctx), given)
            if clash is not None:
                raise UsageError(clash, ctx=ctx)
            for p in self.params:
                if p.opts and ctx.get_parameter_source(p.name) == ParameterSource.COMMANDLINE:
                    why = work_limit_error(_path(ctx), p.opts[0], ctx.params.get(p.name))
                    if why is not None:
                        raise UsageError(why, ctx=ctx)
        return rest

    def get_params(self, ctx):
        params = super().get_params(ctx)
        for p in params:   # the work limits of WORK_LIMITS, stated in --help
            if p.opts and getattr(p, "help", None):
                p.help = limit_help(_path(ctx), p.opts[0], p.help)
        return params


def _spelled(p, value) -> tuple[str, ...]:
    """How option ``p`` was given: its first name, or a flag's negation when off."""
    if getattr(p, "is_flag", False) and p.secondary_opts and value is False:
        return (p.secondary_opts[0],)
    return (p.opts[0],)


def _path(ctx) -> str:
    """The command's name below ``acid``: "fit", "car select" (the key of the work limits)."""
    names = []
    while ctx is not None and ctx.parent is not None:
        names.append(ctx.info_name or "")
        ctx = ctx.parent
    return " ".join(reversed(names))


class AcidTyper(typer.Typer):
    """Typer whose commands are ``AcidCommand`` unless told otherwise."""

    def command(self, *args, cls=None, **kwargs):
        return super().command(*args, cls=cls or AcidCommand, **kwargs)

    def __call__(self, *args, **kwargs):
        # Ctrl-C after start-up but before a command's InterruptGuard (typer building the
        # command tree: a fraction of a second, seconds on a busy machine) arrives as a
        # KeyboardInterrupt outside every command: the same quiet exit as during start-up
        # (130, one line), nothing having been written yet. However the command ends, the
        # process ends through _signals.finish (a signal during the exit is 130 / 143 too)
        if kwargs.get("standalone_mode") is False:  # a caller in Python: its process, its end
            return super().__call__(*args, **kwargs)
        fix_process()  # acid's own process: one BLAS thread for the run (acid._blas)
        code: object = 0
        try:
            try:
                super().__call__(*args, **kwargs)
            except SystemExit as exc:
                code = exc.code
            except KeyboardInterrupt:
                raise
            except Exception:  # a bug outside every command: its trace, exit 1
                sys.excepthook(*sys.exc_info())
                code = 1
            _signals.finish(code)  # its first act installs the handlers of the exit
        except KeyboardInterrupt:
            _signals.exit_interrupted()


class AcidGroup(FlagsTakeNoValue, TyperGroup):
    """Typer's group, with usage errors (unknown option, bad integer, missing argument) as one
    ``error:`` line naming the option, like every other acid error, instead of a panel."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True,
             **extra):
        if not standalone_mode:
            return super().main(args=args, prog_name=prog_name, complete_var=complete_var,
                                standalone_mode=False, **extra)
        try:
            rv = super().main(args=args, prog_name=prog_name, complete_var=complete_var,
                              standalone_mode=False, **extra)
        except ClickException as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":  # bare `acid`: the help, as usual
                typer.echo(exc.ctx.get_help() if exc.ctx else str(exc), err=True)
                sys.exit(exc.exit_code)
            where = f" (see `{exc.ctx.command_path} --help`)" if getattr(exc, "ctx", None) else ""
            error_line(f"{exc.format_message()}{where}")
            sys.exit(exc.exit_code)
        except typer.Abort:
            sys.exit(130)
        sys.exit(rv if isinstance(rv, int) else 0)


app = AcidTyper(
    name="acid",
    cls=AcidGroup,
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


# The sub-commands, one line each in acid_cli.commands (sorted by pipeline).
from acid_cli.commands import register  # noqa: E402

register(app)

_signals.end_startup()
