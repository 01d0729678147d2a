"""The wheel carries every package: each folder of acid/ and cli/ with an ``__init__.py`` is
listed in pyproject.toml's explicit ``packages`` (a package left out installs from a clone but
not from the wheel: acid.control was, once)."""

from __future__ import annotations

from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).parents[1]


def test_every_package_folder_is_in_the_wheel():
    setup = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setup["packages"])
    roots = {folder: name for name, folder in setup["package-dir"].items()}
    found = set()
    for folder, name in roots.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder)
            found.add(".".join((name, *rel.parts)))
    assert found - listed == set(), f"packages missing from pyproject.toml: {found - listed}"
