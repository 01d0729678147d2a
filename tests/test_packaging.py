"""The wheel ships every package of the source tree (a package missing from pyproject's list
is absent from an installed acid, while the editable install of the repository hides it)."""

from __future__ import annotations

from pathlib import Path

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).parents[1]


def _source_packages() -> set[str]:
    found = set()
    for init in (ROOT / "acid").rglob("__init__.py"):
        parts = init.parent.relative_to(ROOT).parts
        found.add(".".join(parts))
    for init in (ROOT / "cli").rglob("__init__.py"):
        found.add(".".join(("acid_cli", *init.parent.relative_to(ROOT / "cli").parts)))
    return found


def test_every_source_package_is_in_the_wheel():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())
                 ["tool"]["setuptools"]["packages"])
    missing = sorted(_source_packages() - listed)
    assert not missing, f"packages not in pyproject's [tool.setuptools] packages: {missing}"
