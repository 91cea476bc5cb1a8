"""The packages' import graph has no cycle, counting imports inside functions (a lazy import that
points back is still a cycle) and imports under ``if TYPE_CHECKING:`` (an annotation that points
back is a dependency too: the two modules still need each other to be understood). Some tests
below read the runtime graph, which leaves ``TYPE_CHECKING`` blocks out."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("cadsim", "eval", "matchers")


def _modules() -> dict[str, Path]:
    found = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, type_checking: bool = False):
    """Every Import/ImportFrom node; ``if TYPE_CHECKING:`` bodies only with ``type_checking``."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if not type_checking and isinstance(node, ast.If) and _is_type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def import_graph(type_checking: bool = False) -> dict[str, set[str]]:
    """module -> the project modules it imports (``from pkg import sub`` counts as ``pkg.sub``);
    with ``type_checking``, imports under ``if TYPE_CHECKING:`` count too."""
    modules = _modules()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        deps: set[str] = set()
        for node in _imports(ast.parse(path.read_text(), str(path)), type_checking):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                if node.level:
                    base = name.split(".") if is_package else name.split(".")[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                targets = [
                    f"{module}.{alias.name}" if f"{module}.{alias.name}" in modules else module
                    for alias in node.names
                ]
            deps |= {t for t in targets if t in modules and t != name}
        graph[name] = deps
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle as [a, b, ..., a], or None (iterative depth-first search)."""
    state: dict[str, int] = {}  # 1 = on the current path, 2 = done
    for start in sorted(graph):
        if state.get(start):
            continue
        path, iters = [start], [iter(sorted(graph[start]))]
        state[start] = 1
        while path:
            nxt = next(iters[-1], None)
            if nxt is None:
                state[path.pop()] = 2
                iters.pop()
            elif state.get(nxt) == 1:
                return path[path.index(nxt) :] + [nxt]
            elif not state.get(nxt):
                state[nxt] = 1
                path.append(nxt)
                iters.append(iter(sorted(graph[nxt])))
    return None


# Cycles known and not yet resolved (none: reader <-> multi_view and localisation -> gnss_error
# -> pose_error -> localisation were, issue 40). Shrink it; never grow it.
KNOWN_CYCLES: set[frozenset[str]] = set()


def _cycles(graph: dict[str, set[str]]) -> set[frozenset[str]]:
    """The modules of each strongly connected component of more than one module (or a
    self-import): every set of modules that import each other in a circle."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = set()
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    members = set()
                    while True:
                        member = stack.pop()
                        members.add(member)
                        if member == node:
                            break
                    if len(members) > 1 or node in graph[node]:
                        found.add(frozenset(members))
            elif child not in index:
                index[child] = low[child] = len(index)
                stack.append(child)
                work.append((child, iter(sorted(graph[child]))))
            elif child in stack:
                low[node] = min(low[node], index[child])
    return found


def test_no_import_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_no_import_cycles_through_type_checking_imports_either():
    graph = import_graph(type_checking=True)
    new = _cycles(graph) - KNOWN_CYCLES
    assert not new, "import cycles: " + "; ".join(" <-> ".join(sorted(c)) for c in new)
    assert not KNOWN_CYCLES - _cycles(graph), "a known cycle is gone: remove it from KNOWN_CYCLES"


def test_cycle_finder_sees_an_annotation_that_points_back():
    assert _cycles({"a": {"b"}, "b": {"a"}, "c": {"a"}}) == {frozenset("ab")}
    assert _cycles({"a": {"b"}, "b": set()}) == set()
    tree = ast.parse("if TYPE_CHECKING:\n    import cadsim.world\n")
    assert [n.names[0].name for n in _imports(tree, type_checking=True)] == ["cadsim.world"]


def test_detector_finds_a_lazy_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_function_level_imports_count_and_type_checking_ones_do_not():
    tree = ast.parse(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    import cadsim.world\n"
        "def f():\n    from matchers import problem\n"
    )
    names = [n.module or n.names[0].name for n in _imports(tree)]
    assert "matchers" in names and "cadsim.world" not in names


def test_matchers_import_nothing_from_cadsim_or_eval():
    graph = import_graph()
    leaks = {
        (m, d)
        for m, deps in graph.items()
        if m.startswith("matchers")
        for d in deps
        if d.startswith(("cadsim", "eval"))
    }
    assert not leaks


def test_sources_import_no_other_source():
    graph = import_graph()
    kinds = {
        m.split(".")[2] for m in graph if m.startswith("cadsim.sources.") and m.count(".") >= 3
    }
    for module, deps in graph.items():
        if module.startswith("cadsim.sources.") and module.count(".") >= 3:
            own = module.split(".")[2]
            others = {d for d in deps if d.count(".") >= 3 and d.split(".")[2] in kinds - {own}}
            assert not others, f"{module} imports another source: {sorted(others)}"


def folder_graph(package: str) -> dict[str, set[str]]:
    """Folder -> the folders its modules import, inside `package` (a module counts for the folder
    it sits in, the package root being a folder of its own; ``__init__.py`` re-exports aside)."""
    modules = _modules()
    graph: dict[str, set[str]] = {}

    def folder(name: str) -> str:
        path = modules[name]
        return ".".join(path.relative_to(ROOT).parent.parts)

    for name, deps in import_graph().items():
        if not name.startswith(package) or modules[name].name == "__init__.py":
            continue
        own = folder(name)
        graph.setdefault(own, set())
        for dep in deps:
            if dep.startswith(package) and modules[dep].name != "__init__.py":
                if folder(dep) != own:
                    graph[own].add(folder(dep))
    return graph


@pytest.mark.parametrize("package", ["matchers", "eval"])
def test_no_loop_between_the_folders_of_a_package(package):
    cycle = find_cycle(folder_graph(package))
    assert cycle is None, "folder loop: " + " -> ".join(cycle)


def test_algorithms_import_blocks_never_the_reverse():
    graph = folder_graph("matchers")
    for sub in ("matchers.core", "matchers.hypergraph", "matchers.blocks"):
        assert "matchers" not in graph.get(sub, set()), f"{sub} imports an algorithm"
    assert "matchers.hypergraph" not in graph["matchers.core"]
    assert "matchers.blocks" not in graph["matchers.hypergraph"]


def test_the_algorithms_are_what_the_matchers_folder_shows():
    top = sorted(p.name for p in (ROOT / "matchers").glob("*.py"))
    below = [p for p in (ROOT / "matchers").glob("*/*.py") if p.name != "__init__.py"]
    assert len(top) <= 24 and len(below) >= 8, (top, len(below))
    assert len(list((ROOT / "eval").glob("*.py"))) <= 8


def test_the_learned_matchers_are_one_sub_package():
    """``matchers/learned/`` holds the learned matchers (matcher, unary, features, model, trees,
    booster, training); it builds on the algorithms and blocks, and nothing in ``matchers``
    imports it (the registry names it by string), so it sits on top of the folder graph."""
    assert not list((ROOT / "matchers").glob("learned*.py"))
    graph = folder_graph("matchers")
    assert graph["matchers.learned"] <= {"matchers", "matchers.blocks", "matchers.core"}
    users = {folder for folder, deps in graph.items() if "matchers.learned" in deps}
    assert not users, users
    from matchers import get

    for name in ("learned", "learned_pose", "maximin_learned", "rrwm_learned"):
        assert get(name).__module__.startswith("matchers.learned.")
