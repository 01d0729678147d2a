"""The layout of ``ARCHITECTURE.md``, read from the code: no import circle, no import against
the layer order, no private name imported across files, no room above 12 % of the lines, and
the old import paths working (with a warning) as aliases of the new modules.

The imports are read with ``ast`` (module level and inside functions alike), so a circle that
only closes at run time is still a circle here.
"""

from __future__ import annotations

import ast
import functools
import subprocess
import sys
from pathlib import Path

import pytest

from acid._compat import MOVED, PACKAGES

ROOT = Path(__file__).resolve().parents[1]

#: the layers, lowest first: a module may import its own layer and the ones below it
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("core", ("acid", "acid._io", "acid._readers", "acid._compat", "acid.errors", "acid.units",
              "acid.metrics", "acid.numbers", "acid.expr", "acid.psychro", "acid.comfort",
              "acid.examples", "acid.signals", "acid.data", "acid.logcheck", "acid.outdir",
              "acid.executor", "acid.pipeline", "acid.paper", "acid.datasets")),
    ("models", ("acid.models",)),
    ("plant", ("acid.plant", "acid.excite")),
    ("ident", ("acid.ident",)),
    ("control", ("acid.control",)),
    ("claims", ("acid.claims",)),
    ("studies", ("acid.studies",)),
    ("report", ("acid.report",)),
    # the runs that write a report: reproduce and the sweep's runner (and the package that
    # offers run_sweep)
    ("runs", ("=acid.studies.reproduce", "=acid.studies.sweep.runner", "=acid.studies.sweep")),
    ("cli", ("acid_cli",)),
)

#: the old paths (two-line aliases and re-exporting packages): outside the layers
OLD = set(MOVED) | set(PACKAGES)


def _modules() -> dict[str, Path]:
    mods = {}
    for pkg, folder in (("acid", ROOT / "acid"), ("acid_cli", ROOT / "cli")):
        for p in folder.rglob("*.py"):
            parts = [pkg, *p.relative_to(folder).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts = parts[:-1]
            mods[".".join(parts)] = p
    return mods


MODULES = _modules()


def _resolve(name: str) -> str | None:
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


@functools.cache  # three tests read every file: parsed once
def _imports(path: Path) -> tuple[tuple[str, str, int], ...]:
    """(module imported, name imported or '', line) of every ``acid`` import in ``path``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out += [(a.name, "", node.lineno) for a in node.names
                    if a.name.split(".")[0] in ("acid", "acid_cli")]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level \
                and node.module.split(".")[0] in ("acid", "acid_cli"):
            out += [(node.module, a.name, node.lineno) for a in node.names]
    return tuple(out)


def _graph() -> dict[str, dict[str, int]]:
    """module -> {module it imports: line}."""
    graph: dict[str, dict[str, int]] = {}
    for mod, path in MODULES.items():
        edges = graph.setdefault(mod, {})
        for module, name, line in _imports(path):
            full = f"{module}.{name}"
            target = _resolve(full if full in MODULES else module)
            if target and target != mod:
                edges.setdefault(target, line)
    return graph


def _layer(mod: str) -> int:
    best, size = None, -1
    for i, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            exact = p.startswith("=")
            p = p.lstrip("=")
            hit = mod == p or (not exact and mod.startswith(p + "."))
            if hit and (len(p) > size or (exact and len(p) == size)):
                best, size = i, len(p)
    assert best is not None, f"{MODULES[mod].relative_to(ROOT)}: in no layer of {__file__}"
    return best


def _where(mod: str) -> str:
    return str(MODULES[mod].relative_to(ROOT))


def _cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10 * len(graph)))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circle():
    graph = {m: e for m, e in _graph().items() if m not in OLD}
    circles = _cycles(graph)
    described = []
    for comp in circles:
        arrows = [f"{_where(a)}:{graph[a][b]} imports {_where(b)}"
                  for a in comp for b in comp if b in graph[a]]
        described.append("; ".join(arrows))
    assert not circles, "import circles:\n" + "\n".join(described)


def test_no_import_against_the_layer_order():
    bad = []
    for mod, edges in _graph().items():
        if mod in OLD:
            continue
        for target, line in edges.items():
            if target in OLD:
                bad.append(f"{_where(mod)}:{line} imports the old path {target} "
                           f"(now {MOVED.get(target, PACKAGES.get(target))})")
            elif _layer(target) > _layer(mod):
                bad.append(f"{_where(mod)}:{line} ({LAYERS[_layer(mod)][0]}) imports "
                           f"{_where(target)} ({LAYERS[_layer(target)][0]})")
    assert not bad, "imports against the layer order:\n" + "\n".join(sorted(bad))


def test_no_private_name_imported_across_files():
    bad = []
    for mod, path in MODULES.items():
        for module, name, line in _imports(path):
            if name.startswith("_") and name != "__version__" \
                    and f"{module}.{name}" not in MODULES:
                bad.append(f"{_where(mod)}:{line} imports {name} from {module}")
    assert not bad, "private names imported across files:\n" + "\n".join(bad)


def test_no_room_holds_more_than_12_percent_of_the_lines():
    """A room is a package's own modules (not its sub-packages), a top-level module of acid,
    or the CLI."""
    rooms: dict[str, int] = {}
    for mod, path in MODULES.items():
        if mod in OLD:
            continue
        room = "cli" if mod.startswith("acid_cli") else (
            str(path.parent.relative_to(ROOT)) if path.parent != ROOT / "acid"
            else str(path.relative_to(ROOT)))
        rooms[room] = rooms.get(room, 0) + len(path.read_text().splitlines())
    total = sum(rooms.values())
    big = {r: f"{100 * n / total:.1f} %" for r, n in rooms.items() if n > 0.12 * total}
    assert not big, f"rooms above 12 % of {total} lines: {big}"


def test_the_old_folders_hold_only_aliases():
    """acid/mpc, acid/sweep and acid/econ keep the old import paths for one release and hold
    no code of their own: controllers live under acid/control, studies under acid/studies."""
    for folder in ("mpc", "sweep", "econ"):
        for p in (ROOT / "acid" / folder).glob("*.py"):
            mod = ".".join(["acid", folder] + ([] if p.stem == "__init__" else [p.stem]))
            assert mod in OLD, f"{p.relative_to(ROOT)} is not an alias (acid._compat.MOVED)"
            assert len(p.read_text().splitlines()) <= 40, f"{p.relative_to(ROOT)}: code?"


def test_every_alias_points_at_a_module_that_exists():
    for old, new in MOVED.items():
        assert new in MODULES, f"{old} -> {new}: no such module"
        assert old in MODULES, f"{old}: its alias file is missing"


@pytest.mark.parametrize("old", ["acid.mpc.nmpc", "acid.mpc.cav_study", "acid.sweep.spec",
                                 "acid.params", "acid.analysis", "acid.econ.params",
                                 "acid.plant.fmu"])
def test_an_old_import_path_warns_and_is_the_new_module(old):
    new = MOVED[old]
    code = (f"import warnings; warnings.simplefilter('error');\n"
            f"try:\n    import {old}\nexcept FutureWarning as w:\n    print('warned', w)\n"
            f"warnings.simplefilter('ignore')\nimport importlib, {old.rsplit('.', 1)[0]}\n"
            f"old = importlib.import_module('{old}'); new = importlib.import_module('{new}')\n"
            f"print('same' if old is new or all(getattr(old, n) is getattr(new, n) for n in "
            f"dir(new) if not n.startswith('_') and hasattr(old, n)) else 'different')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert "warned" in out.stdout and new.split(".")[1] in out.stdout
    assert out.stdout.strip().endswith("same")


def test_the_layer_test_finds_a_circle_and_an_import_upwards():
    """The checks above can fail: a made-up graph with a circle and a model importing a study."""
    graph = {"a": {"b": 1}, "b": {"c": 2}, "c": {"a": 3}, "d": {}}
    assert _cycles(graph) == [["a", "b", "c"]]
    assert _layer("acid.models.paper") < _layer("acid.studies.cav_study")
    assert _layer("acid.studies.sweep.spec") < _layer("acid.report.sweep") \
        < _layer("acid.studies.sweep.runner")
