"""Every table a command prints has column headings a reader can read: no Python identifier
(``verdict_text``, ``c_status_ok``) reaches a heading. Checked on the source of every
`print_table` call whose headings are written out, so a rename inside the code cannot leak
into what the user sees."""
from __future__ import annotations

import ast
import re
from pathlib import Path

CLI = Path(__file__).resolve().parents[1] / "cli"
IDENTIFIER = re.compile(r"^_?[a-z][a-z0-9]*(_[a-z0-9]+)+$")


def _headings() -> list[tuple[str, int, str]]:
    found = []
    for path in sorted(CLI.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if (isinstance(node, ast.Call) and getattr(node.func, "id", None) == "print_table"
                    and len(node.args) >= 2 and isinstance(node.args[1], ast.List)):
                found += [(path.name, el.lineno, el.value) for el in node.args[1].elts
                          if isinstance(el, ast.Constant) and isinstance(el.value, str)]
    return found


def test_headings_are_found():
    assert len(_headings()) > 100          # the check sees the commands' tables


def test_no_heading_is_a_python_identifier():
    bad = [f"{f}:{line} {h!r}" for f, line, h in _headings() if IDENTIFIER.match(h)]
    assert not bad, "column headings that read as code: " + ", ".join(bad)
