"""The documentation site builds from the repository with one command, every example on it
executes (markdown-exec renders a failing example as a traceback, which fails this test), every
CLI command has its help on the command-line page and every public module named in the API
reference exists."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(
    any(importlib.util.find_spec(m) is None for m in ("mkdocs", "mkdocstrings", "markdown_exec")),
    reason="mkdocs, mkdocstrings or markdown-exec not installed (pip install -e '.[test]')")


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(out)],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    return out


def test_the_site_builds_strictly_and_every_example_executes(site):
    pages = sorted(site.rglob("index.html"))
    assert len(pages) >= 7
    for page in pages:
        text = page.read_text()
        assert "Traceback (most recent call last)" not in text, page
    models = (site / "models" / "index.html").read_text()
    assert "two_tanks (fit-oe)" in models and "true 0.0012" in models


def test_every_command_has_its_help_on_the_command_line_page(site):
    from typer.main import get_command

    from acid_cli.main import app

    page = (site / "cli" / "index.html").read_text()
    for name in get_command(app).commands:
        assert f"$ acid {name} --help" in page, name
        assert re.search(rf"Usage: acid {re.escape(name)} \[OPTIONS\]", page), name
