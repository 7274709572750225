"""The package is layered: no import cycle inside ``ecattool/``, between modules or between packages, and every
package imports on its own (docs/architecture.md draws the layers).

What counts as an import: every ``import``/``from … import`` statement in a module, wherever it stands —
module level, inside a function (a lazy import, used to keep start-up fast) or under ``if TYPE_CHECKING:``.
A lazy or type-only import is still a dependency: the two modules cannot be read, tested or moved apart, and a
cycle through one only waits for someone to hoist the import. What does not count: the implicit import of a
package's ``__init__`` that Python performs before ``ecattool.a.b`` (``__init__`` re-exports its submodules by
design; it is a node of its own, reached only by importing the package by name).
"""

from __future__ import annotations

import ast
import functools
import subprocess
import sys
from collections.abc import Iterator, Mapping, Set
from pathlib import Path

PKG = Path(__file__).resolve().parent.parent / "ecattool"


def _modules() -> dict[str, Path | None]:
    """Dotted module name → file (None for a namespace package directory without ``__init__.py``)."""
    mods: dict[str, Path | None] = {}
    for path in sorted(PKG.rglob("*.py")):
        parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        mods[".".join(parts)] = path
    for name in list(mods):
        parts = name.split(".")
        for i in range(1, len(parts)):
            mods.setdefault(".".join(parts[:i]), None)
    return mods


def _imported_names(tree: ast.AST, module: str, is_package: bool, mods: dict[str, Path | None]) -> Iterator[str]:
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            for alias in node.names:  # `from a import b`: the module a.b where b is one, else a
                yield f"{source}.{alias.name}" if f"{source}.{alias.name}" in mods else source


@functools.cache
def import_graph() -> dict[str, frozenset[str]]:
    """Module → the ecattool modules it imports (resolved to the deepest existing module)."""
    mods = _modules()
    graph: dict[str, set[str]] = {name: set() for name in mods}
    for name, path in mods.items():
        if path is None:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for target in _imported_names(tree, name, path.name == "__init__.py", mods):
            while target and target not in mods:
                target = target.rpartition(".")[0]
            if target.startswith("ecattool") and target != name:
                graph[name].add(target)
    return {name: frozenset(targets) for name, targets in graph.items()}


def cycles(graph: Mapping[str, Set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one node (Tarjan, iterative), each as one cycle path."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(component)
    return [_path(graph, c) for c in found]


def _path(graph: Mapping[str, Set[str]], component: set[str]) -> list[str]:
    """One concrete cycle through the component's smallest member, for a readable failure."""
    start = min(component)
    parents: dict[str, str] = {}
    queue = [start]
    while queue:
        node = queue.pop(0)
        for nxt in sorted(graph[node] & component):
            if nxt == start:
                path = [node]
                while path[-1] != start:
                    path.append(parents[path[-1]])
                return [*reversed(path), start]
            if nxt not in parents:
                parents[nxt] = node
                queue.append(nxt)
    raise AssertionError(f"no cycle through {start}")  # pragma: no cover - a component always has one


def room(module: str) -> str:
    """The package (or base module) a module belongs to: ``ecattool.sim.cia402`` → ``ecattool.sim``."""
    return ".".join(module.split(".")[:2])


def test_no_module_imports_itself_back() -> None:
    found = cycles(import_graph())
    assert not found, "import cycles inside ecattool/:\n" + "\n".join(" -> ".join(c) for c in found)


def test_packages_import_only_downward() -> None:
    graph = import_graph()
    rooms: dict[str, set[str]] = {}
    for module, targets in graph.items():
        for target in targets:
            if room(target) != room(module):
                rooms.setdefault(room(module), set()).add(room(target))
                rooms.setdefault(room(target), set())
    found = cycles(rooms)
    witnesses = [
        f"{a} -> {b}: " + ", ".join(f"{m} imports {t}" for m, ts in sorted(graph.items()) for t in sorted(ts)
                                     if room(m) == a and room(t) == b)
        for c in found for a, b in zip(c, c[1:])
    ]
    assert not found, "packages import each other:\n" + "\n".join(
        " -> ".join(c) for c in found) + "\n" + "\n".join(witnesses)


def _diagram_rows() -> list[list[str]]:
    """The rows of the layer diagram in docs/architecture.md ("## Layers"), top first, as room names."""
    text = (PKG.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    block = text.split("## Layers", 1)[1].split("```", 2)[1]
    rows = []
    for line in block.strip().splitlines():
        names = line.split("(", 1)[0].split("·")
        rows.append([n.strip() if n.strip() == "ecattool" else f"ecattool.{n.strip()}" for n in names])
    return rows


def test_the_documented_layers_match_the_code() -> None:
    rows = _diagram_rows()
    row_of = {name: i for i, names in enumerate(rows) for name in names}
    graph = import_graph()
    missing = sorted({room(m) for m in graph} - set(row_of))
    assert not missing, f"docs/architecture.md's layer diagram (## Layers) has no row for {missing}: add one"
    upward = sorted(f"{m} imports {t}" for m, ts in graph.items() for t in ts
                    if room(m) != room(t) and row_of[room(t)] <= row_of[room(m)])
    assert not upward, ("imports that do not go down the documented layers: move the importing package's row above "
                        "the imported one in docs/architecture.md (## Layers) where that is the design, or import "
                        "downward:\n" + "\n".join(upward))


def test_the_walk_sees_lazy_and_type_only_imports() -> None:
    # the graph must include imports inside functions and under TYPE_CHECKING, or cycles through them hide
    graph = import_graph()
    assert "ecattool.yamlloc" in graph["ecattool.sw.build"]  # imported inside a function
    assert "ecattool.esi.model" in graph["ecattool.sii.checks"]  # imported under TYPE_CHECKING only
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c", "a"]]


# A fresh interpreter imports the packages and the base modules each on its own, forked from a parent that has
# loaded the third-party libraries but no ecattool module (one interpreter start, one fork per name).
_IMPORT_ALONE = r"""
import os, sys, traceback
for lib in ("yaml", "pydantic", "click", "lxml.etree", "rich"):
    try:
        __import__(lib)
    except ImportError:
        pass
assert not [m for m in sys.modules if m == "ecattool" or m.startswith("ecattool.")]
failed = []
for name in sys.argv[1:]:
    pid = os.fork()
    if pid == 0:
        try:
            __import__(name)
        except BaseException:
            traceback.print_exc()
            os._exit(1)
        os._exit(0)
    if os.waitpid(pid, 0)[1]:
        failed.append(name)
print(" ".join(failed))
"""


def test_each_package_imports_alone() -> None:
    mods = _modules()
    names = sorted(n for n, p in mods.items()
                   if (p is None or p.name == "__init__.py" or n.count(".") == 1) and n != "ecattool.__main__")
    assert {"ecattool.sim", "ecattool.sii", "ecattool.yamlloc", "ecattool.project"} <= set(names)
    run = subprocess.run([sys.executable, "-c", _IMPORT_ALONE, *names], capture_output=True, text=True,
                         timeout=300, cwd=PKG.parent)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == [], f"these do not import on their own: {run.stdout}\n{run.stderr}"
