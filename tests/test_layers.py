"""The package's layers: each module imports only from its own layer or those below it
(parameters -> model -> fmu -> cosim -> control, fit -> cli; the design's order). Read from the
source's import statements (top-level and inside functions alike), not from what happens to
be loaded."""

from __future__ import annotations

import ast
from pathlib import Path

import wheelterrain

PACKAGE = Path(wheelterrain.__file__).resolve().parent

# rank of each top-level module or subpackage of wheelterrain; a module may import from ranks
# at or below its own
RANK = {
    "__init__": 0, "errors": 0, "data": 0,   # the package's version, errors, shipped data
    "files": 0,                              # files written whole or not at all
    "parameters": 1, "compiled": 1,          # the parameter table; CasADi Functions as C
    "presets": 2,
    "model": 3,
    "fmu": 4, "modelica": 4,                 # the FMUs; the Modelica library
    "cosim": 5,
    "control": 6, "fit": 6, "plots": 6,
    "run": 7,                                # one function per command: engine choice, files
    "cli": 8,
}


def _layer(module: str) -> str:
    """'wheelterrain.model.api' -> 'model'; 'wheelterrain' -> '__init__'."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _imports(path: Path, package: Path = PACKAGE) -> list[tuple[str, int]]:
    """(wheelterrain module imported, line) for every import statement in ``path``, a file of
    the package at ``package``."""
    root = package.parent
    here = ".".join(path.relative_to(root).with_suffix("").parts)
    parent = here if path.name == "__init__.py" else here.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: resolve against this module's package
                anchor = parent.split(".")[: len(parent.split(".")) - node.level + 1]
                base = ".".join([*anchor, *([base] if base else [])])
            for alias in node.names:  # `from wheelterrain import model` imports a subpackage
                child = f"{base}.{alias.name}"
                place = root / Path(*child.split("."))
                is_module = place.is_dir() or place.with_suffix(".py").is_file()
                found.append((child if is_module else base, node.lineno))
    return [(m, line) for m, line in found if m == "wheelterrain" or m.startswith("wheelterrain.")]


def test_every_top_level_module_has_a_rank():
    names = {p.stem if p.suffix == ".py" else p.name for p in PACKAGE.iterdir()
             if (p.suffix == ".py" or (p / "__init__.py").exists())}
    names -= {"fmu_src", "_compiled"}  # shipped FMU sources and build output, not imported
    assert names <= set(RANK), names - set(RANK)


def test_no_module_imports_from_a_higher_layer():
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if "fmu_src" in path.parts:
            continue
        own = _layer(".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts))
        if path.name == "__init__.py" and path.parent == PACKAGE:
            own = "__init__"
        for module, line in _imports(path):
            if RANK[_layer(module)] > RANK[own]:
                upward.append(f"{path.relative_to(PACKAGE)}:{line} ({own}) imports {module}")
    assert not upward, "imports that run up the layers:\n" + "\n".join(upward)


def test_the_check_sees_an_upward_import(tmp_path):
    """The check is not vacuous: an import of fmu/ from inside a function of model/ is found,
    and ranks above it; so is a relative one."""
    fake = tmp_path / "wheelterrain"
    for folder in ("model", "fmu"):
        (fake / folder).mkdir(parents=True)
        (fake / folder / "__init__.py").write_text("")
    (fake / "fmu" / "variables.py").write_text("")
    (fake / "model" / "bad.py").write_text("def f():\n    from wheelterrain.fmu import variables\n"
                                           "from ..fmu import variables\n")
    found = _imports(fake / "model" / "bad.py", fake)
    assert sorted(found) == [("wheelterrain.fmu.variables", 2), ("wheelterrain.fmu.variables", 3)]
    assert RANK[_layer("wheelterrain.fmu.variables")] > RANK["model"]


# --- the structure's measures: modules, import edges, upward imports, cycles -------------------

LAYOUT = Path(__file__).resolve().parents[1] / "docs" / "layout.md"


def _modules(package: Path = PACKAGE) -> dict[str, Path]:
    """Every module of the package by dotted name (a package by its own name), but the
    shipped FMU sources and build output."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        if {"fmu_src", "_compiled"} & set(path.parts):
            continue
        parts = path.relative_to(package.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def module_graph(package: Path = PACKAGE) -> tuple[dict[str, Path], set[tuple[str, str]]]:
    """(modules, import edges a -> b between distinct modules of the package)."""
    modules = _modules(package)
    edges = {(name, target) for name, path in modules.items()
             for target, _ in _imports(path, package) if target in modules and target != name}
    return modules, edges


def cycles(modules, edges) -> list[list[str]]:
    """The import cycles: strongly connected sets of two or more modules (Tarjan)."""
    after = {m: sorted(b for a, b in edges if a == m) for m in modules}
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in after[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for v in sorted(modules):
        if v not in index:
            visit(v)
    return found


def measures() -> dict[str, int]:
    modules, edges = module_graph()
    upward = sum(RANK[_layer(b)] > RANK[_layer(a)] for a, b in edges)
    return {"modules": len(modules), "edges": len(edges), "upward": upward,
            "cycles": len(cycles(modules, edges))}


def structure_line(m: dict[str, int]) -> str:
    return (f"**{m['modules']} modules, {m['edges']} import edges between them, {m['upward']} "
            f"imports up the layers, {m['cycles']} import cycles.**")


def test_there_is_no_import_cycle():
    modules, edges = module_graph()
    assert cycles(modules, edges) == []


def test_the_cycle_check_sees_a_cycle(tmp_path):
    """Not vacuous: a function-level import back to a module that imports it is a cycle."""
    fake = tmp_path / "wheelterrain"
    (fake / "model").mkdir(parents=True)
    (fake / "__init__.py").write_text("")
    (fake / "model" / "__init__.py").write_text("")
    (fake / "model" / "a.py").write_text("from wheelterrain.model import b\n")
    (fake / "model" / "b.py").write_text("def f():\n    from wheelterrain.model import a\n")
    modules, edges = module_graph(fake)
    assert cycles(modules, edges) == [["wheelterrain.model.a", "wheelterrain.model.b"]]


def test_the_layout_names_every_module_with_its_layer():
    """docs/layout.md's table has a row per module (its path under src/wheelterrain) with the
    layer the test ranks it in, and no row for a module that is gone."""
    rows = {}
    for line in LAYOUT.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0].startswith("`") and cells[0].endswith(".py`"):
            rows[cells[0].strip("`")] = cells[1]
    expected = {}
    for name, path in _modules().items():
        relative = path.relative_to(PACKAGE).as_posix()
        own = "__init__" if name == "wheelterrain" else _layer(name)
        expected[relative] = str(RANK[own])
    missing = sorted(set(expected) - set(rows))
    gone = sorted(set(rows) - set(expected))
    assert not missing, f"docs/layout.md does not name {missing}"
    assert not gone, f"docs/layout.md names modules that are gone: {gone}"
    wrong = {k: (rows[k], expected[k]) for k in expected if rows[k] != expected[k]}
    assert not wrong, f"docs/layout.md gives these modules another layer (said, ranked): {wrong}"


def test_the_layout_reports_the_measured_structure():
    """The figures docs/layout.md gives (modules, edges, upward imports, cycles) are the
    measured ones."""
    line = structure_line(measures())
    assert line in LAYOUT.read_text(encoding="utf-8"), (
        f"docs/layout.md's structure line is stale; measured: {line}")
