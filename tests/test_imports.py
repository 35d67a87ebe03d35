"""The import structure of pixelkit/: no circle between modules, none between folders, and the
models below the simulator; docs/module-layers.md is drawn from the same walk.

The walk reads every module's source with ``ast`` (every ``import`` and ``from ... import``,
also those inside functions: a lazy import that closes a circle is still a circle) and
resolves relative imports to the modules of the package. Independent path for the layering:
the interpreter itself, importing every model module in a fresh process and listing what
came with it.

Regenerate the page: ``python3 tests/test_imports.py --write``.
"""
import ast
import subprocess
import sys
from pathlib import Path

from conftest import ROOT

PAGE = ROOT / "docs" / "module-layers.md"

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


# --- folders: the floors of the package -------------------------------------------------------

def unit_of(module: str, folders: set) -> str:
    """The unit a module belongs to: its folder under the package (``circuits/``; ``folders``: the
    package's sub-packages), or the file itself for a module at the top of the package
    (``design.py``; the package's own ``__init__.py``)."""
    parts = module.split(".")
    if len(parts) == 1:
        return "__init__.py"
    return parts[1] + ("/" if ".".join(parts[:2]) in folders else ".py")


def unit_graph(root: Path, package: str = "pixelkit") -> tuple[dict, dict]:
    """({unit: units it imports}, {(unit, unit): the module imports behind that edge}), function-level
    imports included."""
    folders = {m for m, (_, is_pkg) in _modules(root, package).items() if is_pkg and m.count(".") == 1}
    graph = import_graph(root, package)
    units, why = {}, {}
    for m, targets in graph.items():
        a = unit_of(m, folders)
        units.setdefault(a, set())
        for t in targets:
            b = unit_of(t, folders)
            if b != a:
                units[a].add(b)
                why.setdefault((a, b), []).append(f"{m} -> {t}")
    return units, why


def floors(units: dict) -> dict:
    """{unit: floor}: 0 for a unit that imports no other, else one above the highest it imports
    (the graph must have no circle)."""
    out = {}

    def floor(u):
        if u not in out:
            out[u] = 1 + max((floor(v) for v in units[u]), default=-1)
        return out[u]
    for u in units:
        floor(u)
    return out


def tie_report(units: dict, why: dict) -> list[str]:
    """One line per set of units that import each other, with the imports that close it."""
    out = []
    for c in circles(units):
        edges = [f"{a} -> {b}: " + ", ".join(sorted(why[a, b])) for a in c for b in c if (a, b) in why]
        out.append(" <-> ".join(c) + " (" + "; ".join(edges) + ")")
    return out


def layers_page(root: Path = ROOT) -> str:
    units, _ = unit_graph(root)
    fl = floors(units)
    rows = []
    for f in range(max(fl.values()) + 1):
        here = sorted(u for u in fl if fl[u] == f)
        for u in here:
            below = ", ".join(f"`{v}`" for v in sorted(units[u], key=lambda v: (-fl[v], v))) or "-"
            rows.append(f"| {f} | `{u}` | {below} |")
    folders = sorted(u for u in units if u.endswith("/"))
    return _PAGE_HEAD.format(n_folders=len(folders), n_files=len(units) - len(folders), top=max(fl.values())) + \
        "\n".join(rows) + "\n" + _PAGE_TAIL


_PAGE_HEAD = """<!-- generated by tests/test_imports.py from the import walk: python3 tests/test_imports.py --write -->
# Module layers: no import circle, the models below the simulator

Rule: every module of `pixelkit/` imports only modules that sit below it, and so does every
folder: no folder imports from a folder that imports from it, directly or round a longer
loop. Each folder then has a floor, and a folder imports only from lower floors. The
analytic models (`pixelkit/physics/`) import nothing of the simulation layer (`spice`,
`camera`, `experiments`, `mc`, `chip`): a model module is importable and testable without
ngspice or the engine. Where a model needs a figure only the simulator gives (the source
follower's small-signal gain A_sf from the BSIM4 models), the caller measures it and passes
it in.

The checks (`tests/test_imports.py`, about 2 s):

- `test_no_import_circle`: reads every module with `ast` (every `import` and
  `from ... import`, also those inside functions: a lazy import that closes a circle is still
  a circle), resolves relative imports, and fails naming each set of modules that import each
  other (strongly connected components).
- `test_no_folder_imports_a_folder_that_imports_it`: the same walk, each module counted in
  its unit (its folder under `pixelkit/`, or the file itself for a module at the top of the
  package, such as `design.py`); it fails naming each set of units that import each other and
  the module imports that close the loop. A function-level import counts: moving an import
  inside a function does not untie two folders.
- `test_module_layers_page_is_the_walk`: this page is generated from that walk; the test fails
  when the code's imports and the page differ.
- `test_models_do_not_reach_the_simulator`: everything a `physics` module can load (its
  imports, lazy ones included, transitively; the packages around each module with their
  import-time statements) contains no simulation-layer module; and, independently, a fresh
  interpreter that imports every `physics` module has no `pixelkit.spice` / `camera` / ...
  module loaded.
- `test_the_walk_finds_circles_and_lazy_imports`, `test_the_folder_walk_finds_ties_and_floors`:
  the checks can fail: on small planted packages with a circle through a function-level and a
  relative import, and two folders tied through a function-level import, they report exactly
  those, and a clean one gets the floors worked by hand.

## The floors, as the walk finds them

{n_folders} folders and {n_files} top-level files; floor 0 imports no other unit of the package,
each other unit sits one floor above the highest unit it imports (floors 0 - {top}). The third
column lists what each imports, highest floor first.

| floor | unit | imports |
|---|---|---|
"""

_PAGE_TAIL = """
## Ties removed (issue 45)

The walk first found six two-way ties between folders and one longer loop; each was cut by
moving the shared piece to the floor where it belongs (no import moved into a function):

| tie | fix |
|---|---|
| `circuits` <-> `physics` | the diffusion geometry and the global-shutter sequence arithmetic (`circuits/geometry.py`, `circuits/timing.py`) moved to `physics/geometry.py`, `physics/timing.py`, below the netlists that draw them (`circuits.testbench` still re-exports `timings`, `GsTiming`) |
| `spice` <-> `tech`, `circuits` <-> `tech` | the EKV fit and the foundry photodiode card's check build decks with `circuits`' devices and run them in ngspice: moved up from `tech/` to `techfit/` (`techfit.ekv.models_for`, `techfit.pdcard.check`); `tech` only describes the process |
| `circuits` <-> `mc` | the mismatch coefficients and sigmas (`coefficients`, `sigma_vth`, `sigma_beta`, `cap_sigma_rel`: the model card read and Pelgrom's law) moved from `mc/pelgrom.py` to `physics/pelgrom.py`; the follower's SPICE gain merged into `camera.spicenoise.sf_gain`, which also cut `camera` -> `mc` -> `chip` -> `camera` |
| `circuits` <-> `families` | the golden-netlist registry gathers both the dual pixel's generators and the families': moved from `circuits/registry.py` to `pixelkit/registry.py`, above both |
| `chip` <-> `sweep` | the task executor (local threads or Dask) moved from `sweep/executors.py` to `spice/executors.py`, below every flow that runs independent decks |
| `design.py` -> `verify` -> `sweep` -> `design.py` | verify's default stimulus moved from `sweep.run` to `chip.scene`, beside `i_floor` |

Earlier cuts (module circles): `physics.fd` / `physics.subpixel` / `physics.noise` no longer
reach `camera.spicenoise` (`model_table(design, a_sf)` takes the SF gain from its caller);
the PD node's parts (`mos_junctions`, `overlap`, `switch_side`, `pd_node`) sit in
`physics/nodes.py` below `fd` and `subpixel`; `cli.entry` registers the commands so
`cli.common` no longer imports its package.

Regenerate: `python3 tests/test_imports.py --write`; check: `python3 -m pytest tests/test_imports.py -q`.
"""


def test_no_folder_imports_a_folder_that_imports_it():
    units, why = unit_graph(ROOT)
    found = tie_report(units, why)
    assert not found, "units that import each other (move the shared piece to the lower one):\n" + "\n".join(found)


def test_module_layers_page_is_the_walk():
    assert PAGE.read_text() == layers_page(), "regenerate with `python3 tests/test_imports.py --write`"


def test_the_folder_walk_finds_ties_and_floors(tmp_path):
    """The check can fail: folder ``a`` imports ``b`` at the top, ``b`` imports ``a`` inside a function
    (a two-way tie, reported with both imports); a clean package gets the floors worked by hand."""
    pkg = tmp_path / "pk"
    for d in ("a", "b", "c"):
        (pkg / d).mkdir(parents=True)
        (pkg / d / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("")
    (pkg / "a" / "x.py").write_text("from ..b.y import f\n")
    (pkg / "b" / "y.py").write_text("def f():\n    from ..a import x\n    return x\n")
    (pkg / "c" / "z.py").write_text("from ..b import y\nfrom .. import top\n")
    (pkg / "top.py").write_text("import os\n")
    units, why = unit_graph(tmp_path, "pk")
    assert tie_report(units, why) == ["a/ <-> b/ (a/ -> b/: pk.a.x -> pk.b.y; b/ -> a/: pk.b.y -> pk.a.x)"]
    (pkg / "b" / "y.py").write_text("def f():\n    from .. import top\n    return top\n")
    units, why = unit_graph(tmp_path, "pk")
    assert tie_report(units, why) == []
    assert floors(units) == {"__init__.py": 0, "top.py": 0, "b/": 1, "a/": 2, "c/": 2}


if __name__ == "__main__":
    if sys.argv[1:] == ["--write"]:
        PAGE.write_text(layers_page())
        print(f"wrote {PAGE.relative_to(ROOT)}")
    else:
        sys.exit("usage: python3 tests/test_imports.py --write")
