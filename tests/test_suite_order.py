"""The suite's own scheduling (tests/conftest.py ``SLOWEST_FIRST``, pyproject's addopts): the
slowest files exist under their listed names and are handed out first."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from conftest import SLOWEST_FIRST, pytest_collection_modifyitems

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

TESTS = Path(__file__).resolve().parent


def test_every_listed_slow_file_exists_once():
    """A renamed or removed file would silently fall back to the end of the queue."""
    assert len(set(SLOWEST_FIRST)) == len(SLOWEST_FIRST)
    missing = [name for name in SLOWEST_FIRST if not (TESTS / name).is_file()]
    assert not missing, f"SLOWEST_FIRST names files that do not exist: {missing}"


def test_files_are_handed_out_in_the_listed_order_by_file():
    """xdist must neither reorder files by test count nor split a file across workers."""
    addopts = tomllib.loads((TESTS.parent / "pyproject.toml").read_text())[
        "tool"]["pytest"]["ini_options"]["addopts"].split()
    assert "--no-loadscope-reorder" in addopts
    assert addopts[addopts.index("--dist") + 1] == "loadfile"


def test_the_hook_puts_the_listed_files_first_in_their_order_and_keeps_the_rest():
    names = ["test_a.py", SLOWEST_FIRST[2], "test_b.py", SLOWEST_FIRST[0], SLOWEST_FIRST[2],
             "test_c.py", SLOWEST_FIRST[1]]
    items = [SimpleNamespace(path=TESTS / n, k=k) for k, n in enumerate(names)]
    pytest_collection_modifyitems(None, items)
    assert [it.path.name for it in items] == [SLOWEST_FIRST[0], SLOWEST_FIRST[1],
                                              SLOWEST_FIRST[2], SLOWEST_FIRST[2],
                                              "test_a.py", "test_b.py", "test_c.py"]
    assert [it.k for it in items if it.path.name == SLOWEST_FIRST[2]] == [1, 4]  # stable
