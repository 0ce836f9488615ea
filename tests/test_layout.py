"""The package's layout: no import cycles, no upward imports, no overlong modules, and an
``import ehlfoam`` without side effects.

The import graph is read from the source (every ``import`` and ``from ... import``, those
inside functions too), not by importing it. An import of a package's name counts as an import
of its ``__init__``; a submodule imported by name (``from ehlfoam.case import fields``) counts
as that module. Importing a submodule runs its parent packages' ``__init__`` too, but those
implicit imports are not edges here: a package's ``__init__`` that re-exports its submodules
would otherwise be in a cycle with every one of them.
"""

from __future__ import annotations

import ast
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "ehlfoam"

#: The layers, bottom to top: a module may import from its own subpackage and from layers
#: below its own, never from one above. The top-level modules not named here
#: (``ehlfoam/__init__.py``, ``ehlfoam/__main__.py``) sit on top of everything.
LAYERS: list[tuple[str, ...]] = [
    ("_io", "_cache_root", "_kernel_cache", "errors", "notices", "paths"),
    ("foam",),
    ("contact",),
    ("spec",),
    ("gap",),
    ("thinfilm",),
    ("tracks",),
    ("mesh",),
    ("case",),
    ("metrics",),
    ("run",),
    ("seed",),
    ("batch",),
    ("report",),
    ("cli",),
]
TOP = len(LAYERS)

#: The longest a module may be, in lines.
MAX_LINES = 500

#: Modules still longer than MAX_LINES, each with its owner: they are being split in another
#: branch ("truth": metrics, run, batch, report). Remove an entry once its module is split.
LONG_MODULES: dict[str, str] = {}

#: Known upward imports in other branches' layers, (importer, imported): owner and fix.
#: Remove an entry once it is fixed.
KNOWN_UPWARD: dict[tuple[str, str], str] = {}

#: Known import cycles in other branches' layers (their modules, sorted): owner and fix.
KNOWN_CYCLES: dict[tuple[str, ...], str] = {}


def _module_names() -> dict[str, Path]:
    """Every module of the package by its dotted name (a package by its own name)."""
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The ehlfoam modules ``name`` imports, anywhere in it."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.split(".")[0] == "ehlfoam")
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "ehlfoam":
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.add(sub if sub in modules else target)
    out.discard(name)
    return out


def _graph() -> dict[str, set[str]]:
    modules = _module_names()
    return {name: _imports(name, path, modules) for name, path in modules.items()}


def _layer(module: str) -> tuple[int, str]:
    """(layer index, subpackage) of a module."""
    parts = module.split(".")
    if len(parts) == 1:
        return TOP, ""
    for i, names in enumerate(LAYERS):
        if parts[1] in names:
            return i, parts[1]
    return TOP, parts[1]


def _cycles(graph: dict[str, set[str]]) -> list[tuple[str, ...]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[tuple[str, ...]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(tuple(sorted(component)))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _upward(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """(importer, imported) pairs where the imported module's layer is above the importer's
    and not its own subpackage."""
    out = []
    for name, targets in sorted(graph.items()):
        layer, sub = _layer(name)
        for target in sorted(targets):
            t_layer, t_sub = _layer(target)
            if t_sub != sub and t_layer > layer:
                out.append((name, target))
    return out


def _long_modules() -> dict[str, int]:
    return {name: len(path.read_text().splitlines())
            for name, path in _module_names().items()
            if len(path.read_text().splitlines()) > MAX_LINES}


def test_the_graph_sees_every_kind_of_import():
    """The scan finds absolute, relative, submodule and in-function imports, so that a test
    below that finds nothing means there is nothing."""
    graph = _graph()
    assert "ehlfoam.case.fields" in graph["ehlfoam.case.writer"]        # from x.y import z
    assert "ehlfoam.case.face_oil" in graph["ehlfoam.case.fields"]       # from x import module
    assert "ehlfoam.thinfilm.state" in graph["ehlfoam.seed.start"]
    assert "ehlfoam.seed.follow" in graph["ehlfoam.batch.case"]          # inside a function
    assert _layer("ehlfoam.errors")[0] < _layer("ehlfoam.foam.runtime")[0] \
        < _layer("ehlfoam.cli.main")[0] < _layer("ehlfoam")[0]


def test_no_import_cycles():
    cycles = [c for c in _cycles(_graph()) if c not in KNOWN_CYCLES]
    assert not cycles, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in cycles)


def test_no_upward_imports():
    """An import goes down the layers or stays within its subpackage."""
    upward = [pair for pair in _upward(_graph()) if pair not in KNOWN_UPWARD]
    assert not upward, "upward imports (see LAYERS):\n" + "\n".join(
        f"{a} -> {b}" for a, b in upward)


def test_no_module_is_longer_than_500_lines():
    long = {name: n for name, n in _long_modules().items() if name not in LONG_MODULES}
    assert not long, "modules over 500 lines: " + ", ".join(
        f"{name} ({n})" for name, n in sorted(long.items()))


def test_the_allowlists_name_only_what_is_still_there():
    """An entry of LONG_MODULES, KNOWN_UPWARD or KNOWN_CYCLES whose problem is gone must go:
    the lists only shrink."""
    graph = _graph()
    stale = ([m for m in LONG_MODULES if m not in _long_modules()]
             + [f"{a} -> {b}" for a, b in KNOWN_UPWARD if (a, b) not in _upward(graph)]
             + [" <-> ".join(c) for c in KNOWN_CYCLES if c not in _cycles(graph)])
    assert not stale, "fixed, remove from the allowlists: " + ", ".join(stale)


def test_import_ehlfoam_loads_no_numpy_and_sets_only_the_kernel_cache_in_the_environment():
    """``import ehlfoam`` loads no numpy, and its one change to the environment is numba's
    cache folder (ehlfoam._kernel_cache), whether or not the process that runs the test has
    set it already (an earlier import in it does)."""
    code = ("import json, os, sys; before = dict(os.environ); import ehlfoam; "
            "print(json.dumps({'numpy': 'numpy' in sys.modules, "
            "'environ': sorted(set(os.environ.items()) ^ set(before.items()))}))")
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONSTARTUP", "NUMBA_CACHE_DIR")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env)
    result = json.loads(out.stdout)
    assert result["numpy"] is False
    assert [k for k, _ in result["environ"]] == ["NUMBA_CACHE_DIR"]
    assert Path(result["environ"][0][1]).parent.name == "numba"


@pytest.mark.parametrize("module", ["ehlfoam.mesh", "ehlfoam.spec", "ehlfoam.thinfilm"])
def test_a_subpackage_has_what_its_all_names(module):
    package = importlib.import_module(module)
    assert [n for n in package.__all__ if not hasattr(package, n)] == []
