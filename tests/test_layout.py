"""The package's shape: its import graph has no cycle (imports inside functions included), no
module imports another package's private names, and package ``__init__`` files only
re-export."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "planner"
MAX_LINES = 450
OVER_LIMIT: set[str] = set()


def _modules() -> dict[str, Path]:
    out = {}
    for p in PACKAGE.rglob("*.py"):
        parts = list(p.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


MODULES = _modules()


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _owner(name: str) -> str:
    """The module that resolves a dotted name (the longest known prefix)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def _type_checking_only(node: ast.AST, parents: dict) -> bool:
    while node in parents:
        node = parents[node]
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            return True
    return False


@functools.cache
def _imports(name: str) -> tuple[tuple[str, str], ...]:
    return tuple(_find_imports(name))


def _find_imports(name: str):
    """(imported module, private name or None) for every import of planner modules in
    ``name``, at any depth (functions included), TYPE_CHECKING blocks left out."""
    tree = ast.parse(MODULES[name].read_text())
    parents = {c: n for n in ast.walk(tree) for c in ast.iter_child_nodes(n)}
    here = name.split(".") if _is_package(name) else name.split(".")[:-1]
    for node in ast.walk(tree):
        if not isinstance(node, ast.Import | ast.ImportFrom) or _type_checking_only(node,
                                                                                    parents):
            continue
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("planner"):
                    yield _owner(a.name), a.name
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(here[: len(here) - node.level + 1] + ([base] if base else []))
            if not base.startswith("planner"):
                continue
            for a in node.names:
                full = f"{base}.{a.name}"
                yield (full, full) if full in MODULES else (_owner(base), full)


def _private_owner(dotted: str) -> str | None:
    """The package a private name belongs to (``planner.x`` for ``planner.x._y`` or for
    ``_z`` defined in module ``planner.x.m``), None for a public name."""
    parts = dotted.split(".")
    for i, seg in enumerate(parts):
        if seg.startswith("_") and not seg.startswith("__"):
            owner = ".".join(parts[:i])
            if owner in MODULES and not _is_package(owner):
                owner = owner.rpartition(".")[0]
            return owner
    return None


def _graph() -> dict[str, set[str]]:
    graph = {m: set() for m in MODULES}
    for m in MODULES:
        for target, _ in _imports(m):
            if target and target != m:
                graph[m].add(target)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
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
    return out


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycles():
    assert _cycles(_graph()) == []


def test_no_module_imports_another_packages_private_names():
    bad = []
    for m in MODULES:
        for _, dotted in _imports(m):
            owner = _private_owner(dotted)
            if owner is not None and not (m == owner or m.startswith(owner + ".")):
                bad.append(f"{m} imports {dotted}")
    assert bad == []


def test_package_init_files_only_re_export():
    allowed_names = {"__all__", "__version__", "_LAZY", "_SUBMODULES"}
    bad = []
    for m, p in MODULES.items():
        if p.name != "__init__.py":
            continue
        for node in ast.parse(p.read_text()).body:
            if isinstance(node, ast.Import | ast.ImportFrom):
                continue
            if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
                continue  # the docstring
            if isinstance(node, ast.Assign | ast.AnnAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                if all(isinstance(t, ast.Name) and t.id in allowed_names for t in targets):
                    continue
            if isinstance(node, ast.FunctionDef) and node.name == "__getattr__":
                continue  # lazy re-exports
            bad.append(f"{m}: line {node.lineno}")
    assert bad == []


def test_modules_stay_small():
    long = {m for m, p in MODULES.items() if len(p.read_text().splitlines()) > MAX_LINES}
    assert long <= OVER_LIMIT, sorted(long - OVER_LIMIT)


def test_imports_inside_functions_say_why():
    """An import of a project module inside a function keeps a heavy library (numba, scipy,
    matplotlib, a format extra) off the import path of its module, and says so."""
    bad = []
    for m, p in MODULES.items():
        lines = p.read_text().splitlines()
        for fn in ast.walk(ast.parse("\n".join(lines))):
            if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.Import | ast.ImportFrom):
                    mod = node.module if isinstance(node, ast.ImportFrom) else node.names[0].name
                    project = bool(node.level) if isinstance(node, ast.ImportFrom) else False
                    if (project or (mod or "").startswith("planner")) and \
                            "#" not in lines[node.lineno - 1]:
                        bad.append(f"{m}:{node.lineno}")
    assert bad == []
