"""``acid examples``: the bundled examples (sweep specifications, import and FMU maps, plant
configurations, a sample log): list them, copy one, or show where one is. Every command also
reads them in place as ``example:NAME``."""

from __future__ import annotations

import shutil
from pathlib import Path

import typer

from acid import examples as bundled
from acid._io import atomic_path
from acid.errors import ConfigError, OutputError
from acid_cli._common import check_paths, handle_errors, print_table, say

ACTIONS = ("list", "copy", "path")


@handle_errors
def examples(
    action: str = typer.Argument("list", metavar="[ACTION]",
                                 help="list (default), copy NAME [DEST], or path NAME."),
    name: str | None = typer.Argument(None, metavar="[NAME]",
                                      help="An example's name, as `acid examples` lists it."),
    dest: Path | None = typer.Argument(None, metavar="[DEST]",
                                       help="copy: the file or folder to copy to (default: "
                                            "NAME in the current folder)."),
    force: bool = typer.Option(False, "--force", help="copy: overwrite an existing DEST."),
) -> None:
    """List the bundled examples, copy one (to edit it), or print where one is.

    Wherever acid reads a file, `example:NAME` names a bundled one, from any folder:
    `acid import example:sample_log.csv.gz --map example:sample_log_map.toml --out run.h5`.
    """
    if action not in ACTIONS:
        raise ConfigError(f"ACTION {action!r} must be one of {', '.join(ACTIONS)}")
    if action == "list":
        if name is not None:
            raise ConfigError(f"NAME {name!r}: `acid examples list` takes no name")
        rows = [[n, *bundled.describe(n)] for n in bundled.available()]
        print_table("bundled examples (use as example:NAME wherever acid reads a file)",
                    ["_name", "_kind", "_what"], rows)
        say("copy one to edit it: acid examples copy NAME [DEST]")
        return
    if name is None:
        raise ConfigError(f"NAME: `acid examples {action}` needs the name of an example")
    # `example:NAME` arrives here already resolved to the bundled file (handle_errors)
    src = bundled.resolve(Path(name).name if bundled.is_bundled(name) else name)
    if action == "path":
        if dest is not None:
            raise ConfigError(f"DEST {dest}: `acid examples path` takes no destination")
        say(str(src))
        return
    target = Path(src.name) if dest is None else (dest / src.name if dest.is_dir() else dest)
    check_paths(inputs={"NAME": src}, outputs={"DEST": target})
    if target.exists() and not force:
        raise OutputError(f"DEST {target}: already exists; --force overwrites it")
    with atomic_path(target) as tmp:
        shutil.copyfile(src, tmp)
    say(f"copied {src.name} to {target}")
