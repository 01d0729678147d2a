"""MkDocs hooks: one page per command of the command line, its help generated at build time
(``acid <command> --help``), and those pages in the navigation under "Command line"."""

from __future__ import annotations

from mkdocs.structure.files import File

_COMMANDS: list[str] = []   # command words, e.g. "car fit"


def _commands():
    from typer.main import get_command

    from acid_cli.main import app

    out = []
    for name, cmd in sorted(get_command(app).commands.items()):
        subs = getattr(cmd, "commands", None)
        out.append(((name,), cmd))
        for sub, subcmd in sorted((subs or {}).items()):
            out.append(((name, sub), subcmd))
    return out


def _help(words: tuple[str, ...]) -> str:
    from typer.testing import CliRunner

    from acid_cli.main import app

    res = CliRunner().invoke(app, [*words, "--help"], env={"COLUMNS": "100", "NO_COLOR": "1"})
    return res.output


def _slug(words: tuple[str, ...]) -> str:
    return "-".join(words)


def on_config(config):
    if not _COMMANDS:
        _COMMANDS.extend(" ".join(words) for words, _ in _commands())
    pages = [{"Overview": "cli.md"}]
    pages += [{f"acid {w}": f"cli/{_slug(tuple(w.split()))}.md"} for w in _COMMANDS]
    nav = []
    for entry in config["nav"] or []:
        if isinstance(entry, dict) and "Command line" in entry:
            nav.append({"Command line": pages})
        else:
            nav.append(entry)
    config["nav"] = nav
    return config


def on_files(files, config):
    for words in _COMMANDS:
        key = tuple(words.split())
        text = _help(key)
        body = (f"# acid {words}\n\nThe command's own help (`acid {words} --help`), generated "
                f"when this page was built.\n\n```text\n$ acid {words} --help\n{text}```\n")
        files.append(File.generated(config, f"cli/{_slug(key)}.md", content=body))
    return files

