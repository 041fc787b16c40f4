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
