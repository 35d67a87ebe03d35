"""The import structure of pixelkit/: no circle, and the models below the simulator.

The walk reads every module's source with ``ast`` (every ``import`` and ``from ... import``,
also those inside functions: a lazy import that closes a circle is still a circle) and
resolves relative imports to the modules of the package. Independent path for the layering:
the interpreter itself, importing every model module in a fresh process and listing what
came with it.
"""
import ast
import subprocess
import sys
from pathlib import Path

from conftest import ROOT

#: The simulation layer and what sits on it; the models (pixelkit.physics) must not reach them.
ABOVE_THE_MODELS = ("pixelkit.spice", "pixelkit.camera", "pixelkit.experiments", "pixelkit.mc", "pixelkit.chip")


def _modules(root: Path, package: str) -> dict:
    """{dotted name: (file, is a package __init__)} of every module under ``root/package``."""
    out = {}
    for f in sorted((root / package).rglob("*.py")):
        parts = list(f.relative_to(root).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_pkg else parts)] = (f, is_pkg)
    return out


def _targets(node, name: str, is_pkg: bool, mods: dict) -> set:
    """The package's modules one import statement of module ``name`` loads (by its text)."""
    if isinstance(node, ast.Import):
        wanted = [a.name for a in node.names]
    else:
        here = name.split(".") if is_pkg else name.split(".")[:-1]
        base = here[:len(here) - node.level + 1] if node.level else []
        prefix = ".".join(base + ([node.module] if node.module else []))
        wanted = [f"{prefix}.{a.name}" if f"{prefix}.{a.name}" in mods else prefix for a in node.names]
    found = set()
    for w in wanted:
        while w and w not in mods:   # an attribute of a module: the module
            w = w.rpartition(".")[0]
        if w and w != name:
            found.add(w)
    return found


def _imports(tree, at_import: bool):
    """The import statements of a module; ``at_import``: only those that run when it is imported
    (not inside a function)."""
    todo = [tree]
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        if at_import and isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        todo.extend(ast.iter_child_nodes(node))


def import_graph(root: Path, package: str = "pixelkit", at_import: bool = False) -> dict:
    """{module: the package's modules it imports}, lazy imports inside functions included unless
    ``at_import``."""
    mods = _modules(root, package)
    graph = {}
    for name, (f, is_pkg) in mods.items():
        graph[name] = set()
        for node in _imports(ast.parse(f.read_text(), str(f)), at_import):
            graph[name] |= _targets(node, name, is_pkg, mods)
    return graph


def circles(graph: dict) -> list:
    """Every set of modules that import each other (strongly connected, Tarjan), each sorted."""
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
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
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _reach(full: dict, at_import: dict, start: str) -> set:
    """What using ``start`` can load: its imports (lazy ones too) and theirs, and the packages
    around each module reached, which run their import-time statements only."""
    seen, todo = set(), [(start, full)]
    while todo:
        m, graph = todo.pop()
        parts = m.split(".")
        parents = {".".join(parts[:k]) for k in range(1, len(parts))} & set(full)
        for n, g in [(n, full) for n in graph.get(m, ())] + [(p, at_import) for p in parents]:
            if (n, id(g)) not in seen:
                seen.add((n, id(g)))
                todo.append((n, g))
    return {n for n, _ in seen}


def test_no_import_circle():
    found = circles(import_graph(ROOT))
    assert found == [], "modules that import each other: " + "; ".join(" <-> ".join(c) for c in found)


def test_the_walk_finds_circles_and_lazy_imports(tmp_path):
    """The check can fail: a package whose modules import each other, one of them inside a
    function and one through a relative 'from . import', and an innocent module beside them."""
    pkg = tmp_path / "pk"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from .sub.b import f\n")
    (pkg / "sub" / "b.py").write_text("def f():\n    from ..c import g\n    return g\n")
    (pkg / "c.py").write_text("from . import a\nimport pk.d\n")
    (pkg / "d.py").write_text("import os\n")
    g = import_graph(tmp_path, "pk")
    assert g["pk.c"] == {"pk.a", "pk.d"} and g["pk.sub.b"] == {"pk.c"}
    assert circles(g) == [["pk.a", "pk.c", "pk.sub.b"]]
    assert import_graph(tmp_path, "pk", at_import=True)["pk.sub.b"] == set()   # only inside f()
    assert _reach(g, import_graph(tmp_path, "pk", at_import=True), "pk.d") == {"pk"}


def test_models_do_not_reach_the_simulator():
    """The models (pixelkit.physics) import nothing of the simulation layer or above it, by the
    walk (package __init__ files followed) and by the interpreter in a fresh process."""
    g, g0 = import_graph(ROOT), import_graph(ROOT, at_import=True)
    physics = sorted(m for m in g if m == "pixelkit.physics" or m.startswith("pixelkit.physics."))
    assert len(physics) > 5
    for m in physics:
        up = sorted(x for x in _reach(g, g0, m) if x.startswith(ABOVE_THE_MODELS))
        assert up == [], f"{m} reaches {up}"
    code = ("import importlib, sys\n"
            f"for m in {physics!r}:\n    importlib.import_module(m)\n"
            f"print(sorted(m for m in sys.modules if m.startswith({ABOVE_THE_MODELS!r})))\n")
    p = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0 and p.stdout.strip() == "[]", p.stdout + p.stderr[-1500:]
