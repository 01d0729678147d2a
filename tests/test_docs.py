"""The documentation site builds from the repository with one command (`mkdocs build
--strict`: a broken link or anchor fails it), every example on it executes (markdown-exec
renders a failing example as a traceback, which fails this test), every CLI command has its
own page with its help, the public benchmark's page shows the published values beside acid's
and every public name has its anchor in the API reference."""

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
        internal = re.search(r"[Ii]ssue \d+|\b(COMPARE|PLANT|SPEC|ARCHITECTURE)\.md|notes/\w", text)
        assert internal is None, f"{page}: cites {internal.group(0)!r}, which a user does not have"
    models = (site / "models" / "index.html").read_text()
    assert "two_tanks (fit-oe)" in models and "true 0.0012" in models


def test_every_command_has_its_own_page_with_its_help(site):
    from typer.main import get_command

    from acid_cli.main import app

    overview = (site / "cli" / "index.html").read_text()
    commands = []
    for name, cmd in get_command(app).commands.items():
        commands.append((name,))
        commands += [(name, sub) for sub in (getattr(cmd, "commands", None) or {})]
    for words in commands:
        slug, line = "-".join(words), " ".join(words)
        page = (site / "cli" / slug / "index.html").read_text()
        assert f"$ acid {line} --help" in page, line
        assert re.search(rf"Usage: acid {re.escape(line)} \[OPTIONS\]", page), line
        assert f'href="{slug}/"' in overview, line


def test_the_benchmark_page_shows_the_published_values_beside_acids(site):
    page = (site / "benchmark" / "index.html").read_text()
    for published in ("95.1089", "203.5034", "20.3935", "-3.1648"):
        assert published in page
    m = re.search(r"M\s+95\.1089\s+([\d.]+)\s+([\d.]+)", page)
    assert m, "the mass row of the published-beside-acid table"
    assert abs(float(m.group(1)) - 95.1089) < 3 * float(m.group(2))
    assert "record 1:" in page and "subspace" in page


def test_every_public_name_has_its_anchor_in_the_reference(site):
    import importlib
    import inspect

    import acid
    import acid.models

    page = (site / "reference" / "index.html").read_text()
    for mod, names in (("acid", acid.__all__), ("acid.models", acid.models.__all__)):
        m = importlib.import_module(mod)
        for name in names:
            obj = getattr(m, name, None)
            if (inspect.isclass(obj) or inspect.isfunction(obj)) \
                    and not obj.__module__.startswith("casadi"):
                assert f'id="{obj.__module__}.{obj.__qualname__}"' in page, f"{mod}.{name}"
