"""The Modelica library (``wheelterrain build --flavor modelica``), checked by rumoca.

- the generator: every CasADi operation of the exported Functions mapped (an unmapped one
  refused by name), deterministic output, every file parsed by rumoca without an error, a
  package.order in every folder naming its classes;
- with the Modelica Standard Library 4.x on MODELICAPATH (the shared archive, unpacked by
  conftest.py; skipped with the reason elsewhere):
  - every generated function (its arguments MSL's SI types), run by rumoca at operating points
    of every preset (each contact form, braking, z = 0, tiny and deep sinkage, the soil's
    memory loading and unloading): bit for bit its CasADi Function, or within 1e-10 relative
    where a substitution (expm1) acts; the derivative functions likewise their CasADi
    Functions, which match CasADi's Jacobians;
  - every example at its own tolerance against its reference (the Python model): 1e-8; the
    records' SI types exist; the components and wheels against the model.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import modelica_points as mp
from wheelterrain import presets
from wheelterrain.model import api, contact, rig
from wheelterrain.model import functions as model_functions
from wheelterrain.modelica import library, reference, translate
from wheelterrain.modelica.names import path as named
from wheelterrain.parameters import NAMES

rumoca = pytest.importorskip("rumoca")

ROOT = "WheelTerrain"


@pytest.fixture(scope="module")
def built(modelica_root) -> Path:
    """The library as `wheelterrain build --flavor modelica` writes it: the folder holding
    WheelTerrain/."""
    return modelica_root


needs_msl = pytest.mark.skipif(reference.find_msl() is None, reason=(
    "needs the Modelica Standard Library 4.x on MODELICAPATH (a folder holding Modelica/, "
    "ModelicaServices/ and Complex.mo, e.g. modelica/ModelicaStandardLibrary at tag v4.1.0)"))


@pytest.fixture(scope="module")
def msl_root(built, tmp_path_factory) -> Path:
    """One root holding MSL and the library side by side (rumoca 0.10 does not resolve a
    class of one root from a class of another)."""
    return reference.one_root(reference.find_msl(), built,
                              tmp_path_factory.mktemp("modelicapath"))


# ---- the generator --------------------------------------------------------------------------

def test_every_operation_of_the_exported_functions_is_mapped():
    for e in library.exported():
        translate.check(e.function)
        if e.derivative is not None:
            translate.check(e.derivative)
    used = set().union(*(translate.operations(e.function) for e in library.exported()))
    assert ca.OP_EXPM1 in used  # the substitution is exercised by the patch form


def test_an_unmapped_operation_or_an_mx_function_is_refused_by_name():
    x = ca.SX.sym("x")
    with pytest.raises(translate.UnmappedOperationError, match="erf"):
        translate.functions(ca.Function("f", [x], [ca.erf(x)]), "f", [translate.Port("x")],
                            [translate.Port("y")], "f")
    m = ca.MX.sym("x")
    with pytest.raises(translate.UnmappedOperationError, match="not an SX Function"):
        translate.check(ca.Function("g", [m], [ca.sin(m)]))
    with pytest.raises(translate.UnmappedOperationError, match="no Modelica literal"):
        translate.functions(ca.Function("h", [x], [x + math.inf]), "h", [translate.Port("x")],
                            [translate.Port("y")], "h")


def test_the_library_is_the_same_bytes_every_time(built, tmp_path):
    again = library.write(tmp_path)
    first = {p.relative_to(built): p.read_bytes() for p in (built / ROOT).rglob("*")
             if p.is_file()}
    second = {p.relative_to(tmp_path): p.read_bytes() for p in again.rglob("*") if p.is_file()}
    assert first.keys() == second.keys()
    assert all(first[k] == second[k] for k in first)


def test_every_file_parses_and_every_folder_orders_its_classes(built):
    files = sorted((built / ROOT).rglob("*.mo"))
    assert len(files) > 40
    for path in files:
        errors = [d for d in rumoca.validate(str(path)) if d.level == "error"]
        assert errors == [], (path, errors[0].message[:500])
    for folder in [built / ROOT, *[p for p in (built / ROOT).rglob("*") if p.is_dir()]]:
        if "Resources" in folder.relative_to(built / ROOT).parts:
            continue  # files, not classes
        listed = (folder / "package.order").read_text().split()
        present = sorted([p.stem for p in folder.glob("*.mo") if p.name != "package.mo"]
                         + [p.name for p in folder.iterdir() if (p / "package.mo").exists()])
        assert sorted(listed) == present, folder


def test_every_example_is_a_diagram_each_component_placed_each_connection_drawn(built):
    """MSL's diagram examples: in every example (and its Utilities) each component declared
    from a class (not a parameter or a variable) has a Placement, and each connect a Line;
    the examples with more than one component join them by connections only (no equation
    naming two components' variables)."""
    examples = sorted((built / ROOT / "Examples").rglob("*.mo"))
    assert len(examples) > 15
    components = connections = 0
    for path in examples:
        text = path.read_text(encoding="utf-8")
        for m in re.finditer(r"^\s+(?:inner |replaceable )?((?:WheelTerrain|Modelica|"
                             r"PlanarMechanics)\.[\w.]+) \w+", text, re.M):
            if m.group(1).rsplit(".", 1)[-1][0].isupper() and ".Units." not in m.group(1):
                end = library._declaration_end(text, m.start())
                assert "Placement(" in text[m.start():end], (path.name, m.group(0))
                components += 1
        for m in re.finditer(r"^\s+connect\(([^;]*);", text, re.M):
            assert "Line(" in m.group(1), (path.name, m.group(0)[:80])
            connections += 1
        body = text.split("\nequation\n", 1)[1] if "\nequation\n" in text else ""
        equations = [e for e in body.split(";") if "=" in e and "connect(" not in e
                     and "annotation(" not in e and "end " not in e]
        if path.parent.name == "FMUTwin":
            assert equations == [], (path.name, equations[:2])
    assert components > 60
    assert connections > 140


def test_every_public_class_is_documented_and_every_component_and_example_has_an_icon(built):
    """MSL's form: Documentation with info and revisions on every class file (the pieces of
    Functions.Internal, not to be called, aside); an Icon on every component, wheel, terrain
    and example."""
    for path in sorted((built / ROOT).rglob("*.mo")):
        if "Internal" in path.parts:
            continue
        text = path.read_text(encoding="utf-8")
        assert "Documentation(info=" in text, path
        assert "revisions=" in text, path
        drawn = {"Components", "Wheels", "Examples"} & set(path.parts) or path.stem == "Terrain"
        if drawn and "partial " not in text.split("\n", 2)[1]:
            assert "Icon(" in text, path


def test_the_substitutions_stay_within_1e_10_of_what_they_replace():
    """expm1 and asinh, which Modelica lacks, as the generated code writes them (evaluated
    here with the same IEEE operations) against numpy's."""
    x = np.concatenate([-np.logspace(-12, 2, 4000), np.logspace(-12, 2, 4000), [0.0]])
    small = np.abs(x) < 1e-5
    expm1 = np.where(small, x + x * x * (0.5 + x / 6.0), np.exp(x) - 1.0)
    assert np.max(np.abs(expm1 - np.expm1(x)) / np.maximum(np.abs(np.expm1(x)), 1e-300)) < 1e-10
    small = np.abs(x) < 1e-4
    asinh = np.where(small, x * (1.0 - x * x / 6.0),
                     np.sign(x) * np.log(np.abs(x) + np.sqrt(x * x + 1.0)))
    assert np.max(np.abs(asinh - np.arcsinh(x)) / np.maximum(np.abs(np.arcsinh(x)), 1e-300)) \
        < 1e-10
    assert set(translate.SUBSTITUTED) == {ca.OP_EXPM1, ca.OP_ASINH}
    assert "1e-5" in translate.SUBSTITUTED[ca.OP_EXPM1]
    assert "1e-4" in translate.SUBSTITUTED[ca.OP_ASINH]


# ---- the kernels, bit for bit -----------------------------------------------------------------

def _derivative_points(points):
    """The points where the contact has a derivative: z > 0 or a yielded soil under the wheel
    (at z = 0 on fresh soil d(entry angle)/dz = d(sqrt(z))/dz is infinite, in CasADi too)."""
    return [(name, x) for name, x in points if x[0] > 0]


def _probe_model(points) -> str:
    """A model evaluating every exported function and the two dispatchers at every point, and
    their derivatives at every point of :func:`_derivative_points`."""
    vectors = {name: presets.load(name).vector() for name in presets.available()}
    lines = ["model Probe"]
    for tag, chosen in (("", points), ("D", _derivative_points(points))):
        P = "{" + ", ".join(library._vector(vectors[name]) for name, _ in chosen) + "}"
        X = "{" + ", ".join(library._vector(x) for _, x in chosen) + "}"
        lines += [f"  parameter Real P{tag}[{len(chosen)}, {len(NAMES)}] = {P};",
                  f"  parameter Real X{tag}[{len(chosen)}, {len(chosen[0][1])}] = {X};"]
    lines.append(f"  parameter Real S[{len(mp.SEED)}] = {library._vector(mp.SEED)};")
    rover_points = mp.rover_points()
    for key, tag in VECTOR_ARGUMENTS.items():
        rows = [np.atleast_1d(pt[key]) for pt in rover_points]
        dims = f"[{len(rows)}, {rows[0].size}]" if rows[0].size > 1 else f"[{len(rows)}]"
        value = ("{" + ", ".join(library._vector(r) for r in rows) + "}" if rows[0].size > 1
                 else library._vector([r[0] for r in rows]))
        lines.append(f"  parameter Real {tag}{dims} = {value};")
        seed = mp.vector_seed(key, rows[0].size)
        lines.append(f"  parameter Real S{tag}{f'[{seed.size}]' if seed.size > 1 else ''} = "
                     f"{library._vector(seed) if seed.size > 1 else library._vector(seed)[1:-1]};")
    vector_values = []
    for e in _vectorial():
        size = e.outputs[0].size
        args = ", ".join(f"{VECTOR_ARGUMENTS[k]}[i{', :' if k != 'position' else ''}]"
                         for k in e.inputs)
        seeds = ", ".join(f"S{VECTOR_ARGUMENTS[k]}" for k in e.inputs
                          if k not in library.PARAMETER_INPUTS)
        lines += [f"  Real {e.name}_v[{len(rover_points)}, {size}];",
                  f"  Real {e.name}_d[{len(rover_points)}, {size}];"]
        vector_values += [f"    {e.name}_v[i, :] = {ROOT}.Functions.{e.name}({args});",
                          f"    {e.name}_d[i, :] = {ROOT}.Functions.{e.name}Der({args}, "
                          f"{seeds});"]
    values, derivatives = [], []
    n, m = len(points), len(_derivative_points(points))
    for e in _scalar():
        size = e.outputs[0].size
        dims, dims_d, row = ((f"[{n}, {size}]", f"[{m}, {size}]", "[i, :]") if size > 1 else
                             (f"[{n}]", f"[{m}]", "[i]"))
        lines.append(f"  Real {e.name}_v{dims};")
        values.append(f"    {e.name}_v{row} = {ROOT}.Functions.{e.name}"
                      f"({_arguments(e.inputs)});")
        if e.derivative is not None:
            seeds = ", ".join(f"S[{mp.COLUMN[k] + 1}]" for k in e.inputs if k != "p")
            lines.append(f"  Real {e.name}_d{dims_d};")
            derivatives.append(f"    {e.name}_d{row} = {ROOT}.Functions.{e.name}Der("
                               f"{_arguments(e.inputs, 'D')}, {seeds});")
    for stem, memory in (("contact", True), ("quasiStatic", False)):
        names = contact.EXPORT_INPUTS[memory]
        size = len(contact.CONTACT_OUTPUTS) + (len(contact.MEMORY_OUTPUTS) if memory else 0)
        seeds = ", ".join(f"S[{mp.COLUMN[k] + 1}]" for k in names if k != "p")
        lines += [f"  Real {stem}_v[{n}, {size}];", f"  Real {stem}_d[{m}, {size}];"]
        values.append(f"    {stem}_v[i, :] = {ROOT}.Functions.{stem}({_arguments(names)});")
        derivatives.append(f"    {stem}_d[i, :] = {ROOT}.Functions.{stem}Der("
                           f"{_arguments(names, 'D')}, {seeds});")
    return "\n".join([*lines, "equation", f"  for i in 1:{n} loop", *values, "  end for;",
                      f"  for i in 1:{m} loop", *derivatives, "  end for;",
                      f"  for i in 1:{len(rover_points)} loop", *vector_values, "  end for;",
                      "end Probe;"]) + "\n"


def _scalar() -> list:
    """The exported functions of scalar inputs and p: evaluated at :func:`_points`."""
    return [e for e in library.exported() if set(e.inputs) <= {*mp.COLUMN, "p"}]


def _vectorial() -> list:
    """The exported functions of the chassis' and the map's vectors: at :func:`_rover_points`."""
    return [e for e in library.exported() if e not in _scalar()]


VECTOR_ARGUMENTS = {"x": "XR", "u": "UR", "r": "RR", "position": "POS", "g": "G"}





def _arguments(names, tag: str = "") -> str:
    return ", ".join(f"P{tag}[i, :]" if k == "p" else f"X{tag}[i, {mp.COLUMN[k] + 1}]"
                     for k in names)


def _casadi_arguments(names, x, p):
    return [p if k == "p" else x[mp.COLUMN[k]] for k in names]


@pytest.fixture(scope="module")
def probed(msl_root, tmp_path_factory):
    """Every generated function at the operating points, in one rumoca model (the functions'
    arguments are Modelica.Units.SI types: MSL on the root)."""
    points = mp.points()
    folder = tmp_path_factory.mktemp("probe")
    (folder / "Probe.mo").write_text(_probe_model(points))
    model = rumoca.Session(roots=[str(msl_root)]).load(str(folder / "Probe.mo"), model="Probe")
    result = model.simulate((0.0, 0.0), dt=1.0)
    return points, result


def _values(result, name, n, size) -> np.ndarray:
    if size == 1:
        return np.array([[result[f"{name}[{i + 1}]"][-1]] for i in range(n)])
    return np.array([[result[f"{name}[{i + 1},{k + 1}]"][-1] for k in range(size)]
                     for i in range(n)])


def _same(got: np.ndarray, ref: np.ndarray, substituted: bool, what: str,
          differences: bool = False) -> None:
    assert np.array_equal(np.isnan(got), np.isnan(ref)), what
    if not substituted:
        mismatch = ~((got == ref) | (np.isnan(got) & np.isnan(ref)))
        assert not mismatch.any(), (what, np.argwhere(mismatch)[:5], got[mismatch][:5],
                                    ref[mismatch][:5])
    else:
        # within 1e-10 of the value; with ``differences`` (an output that is a small difference
        # of large terms) or of the output's largest value over the points: the turning
        # moment's width integral, g(j + s*y) - g(j - s*y), at a contact 1e-7 m deep is
        # ~1e-13 N.m, and the substituted expm1's 1e-11-relative error shows there at 1.3e-9
        # of it (measured)
        finite = ~np.isnan(ref)
        scale = np.maximum(np.abs(ref), 1e-300)
        if differences:
            column = np.max(np.abs(np.where(finite, ref, 0)), axis=0, keepdims=True)
            scale = np.maximum(scale, column)
        assert np.all(np.abs(got - ref)[finite] <= 1e-10 * scale[finite] + 1e-300), what


@needs_msl
@pytest.mark.slow
def test_every_generated_function_is_its_casadi_function_bit_for_bit(probed):
    points, result = probed
    vectors = {name: presets.load(name).vector() for name in presets.available()}
    moving = _derivative_points(points)
    for e in _scalar():
        size = e.outputs[0].size
        substituted = bool(translate.operations(e.function) & set(translate.SUBSTITUTED))
        got = _values(result, f"{e.name}_v", len(points), size)
        ref = np.array([np.array(e.function(*_casadi_arguments(e.inputs, x, vectors[name])),
                                 dtype=float).ravel() for name, x in points])
        lateral = e.name in ("lateral", "lateralMemory")  # the turning moment's width
        _same(got, ref, substituted, e.name, lateral)
        if e.derivative is not None:
            got = _values(result, f"{e.name}_d", len(moving), size)
            seeds = [mp.SEED[mp.COLUMN[k]] for k in e.inputs if k != "p"]
            ref = np.array([np.array(e.derivative(
                *_casadi_arguments(e.inputs, x, vectors[name]), *seeds), dtype=float).ravel()
                for name, x in moving])
            d_sub = bool(translate.operations(e.derivative) & set(translate.SUBSTITUTED))
            _same(got, ref, d_sub, e.name + "Der", lateral)
    rover_points = mp.rover_points()
    for e in _vectorial():
        size = e.outputs[0].size
        got = _values(result, f"{e.name}_v", len(rover_points), size)
        ref = np.array([np.array(e.function(*(pt[k] for k in e.inputs)), dtype=float).ravel()
                        for pt in rover_points])
        _same(got, ref, False, e.name)
        got = _values(result, f"{e.name}_d", len(rover_points), size)
        seeds = [mp.vector_seed(k, np.atleast_1d(rover_points[0][k]).size) for k in e.inputs
                 if k not in library.PARAMETER_INPUTS]
        ref = np.array([np.array(e.derivative(*(pt[k] for k in e.inputs), *seeds),
                                 dtype=float).ravel() for pt in rover_points])
        _same(got, ref, False, e.name + "Der")


@needs_msl
@pytest.mark.slow
def test_the_dispatchers_run_the_form_the_case_picks_and_every_form_is_reached(probed):
    points, result = probed
    vectors = {name: presets.load(name).vector() for name in presets.available()}
    for stem, memory in (("contact", True), ("quasiStatic", False)):
        names = contact.EXPORT_INPUTS[memory]
        case, forms = contact.export_kernels(memory)
        size = forms[0].nnz_out(0)
        got = _values(result, f"{stem}_v", len(points), size)
        reached = set()
        for i, (name, x) in enumerate(points):
            args = _casadi_arguments(names, x, vectors[name])
            form = int(case(*args))
            reached.add(form)
            ref = np.array(forms[form](*args), dtype=float).ravel()
            _same(got[i:i + 1], ref[None, :], form == contact.PATCH, f"{stem} at {x}")
        got = _values(result, f"{stem}_d", len(_derivative_points(points)), size)
        for i, (name, x) in enumerate(_derivative_points(points)):
            args = _casadi_arguments(names, x, vectors[name])
            form = int(case(*args))
            derivative = library._derivative(forms[form], names)
            seeds = [mp.SEED[mp.COLUMN[k]] for k in names if k != "p"]
            ref = np.array(derivative(*args, *seeds), dtype=float).ravel()
            _same(got[i:i + 1], ref[None, :], form == contact.PATCH, f"{stem}Der at {x}")
        assert reached == {contact.ARC, contact.ARC_REVERSAL, contact.PATCH}, (stem, reached)


def test_the_export_kernels_are_the_models_contact_and_steady_state():
    """export_kernels (what the library reproduces) against build().contact_memory and the
    steady state's own contact (1e-12 relative, the lane kernels' tolerance: a kernel is the
    same expression, CSE'd on its own)."""
    fns = model_functions.build()
    for name in presets.available():
        p = presets.load(name).vector()
        case, forms = contact.export_kernels(True)
        width = len(contact.EXPORT_INPUTS[True]) - 1  # the contact's columns of a point
        for _, point in mp.points()[:20]:
            x = point[:width]
            got = np.array(forms[int(case(*x, p))](*x, p), dtype=float).ravel()
            ref = np.array([float(v) for v in fns.contact_memory(*x, p)])
            assert np.allclose(got, ref, rtol=1e-12, atol=1e-12, equal_nan=True), (name, x)
        case, forms = contact.export_kernels(False)
        for slip in (-0.4, 0.1, 0.5):
            steady = np.array([float(v) for v in fns.steady(62.0, slip, p)])
            z = steady[0]
            got = np.array(forms[int(case(z, slip, p))](z, slip, p), dtype=float).ravel()
            ref = steady[1:1 + len(contact.CONTACT_OUTPUTS)]
            assert np.allclose(got, ref, rtol=1e-12, atol=1e-12), (name, slip)


@pytest.mark.slow
def test_each_derivative_function_is_the_casadi_jacobian_times_the_seed():
    rng = np.random.default_rng(7)
    p = presets.load("paper-table2-arc").vector()
    cases = [(e, _casadi_arguments(e.inputs, x, p)) for e in _scalar() if e.derivative
             for _, x in _derivative_points(mp.points())[20:36:3]]
    cases += [(e, [pt[k] for k in e.inputs]) for e in _vectorial() for pt in mp.rover_points()]
    for e, args in cases:
        moving = [k for k, n in enumerate(e.inputs) if n not in library.PARAMETER_INPUTS]
        sizes = [e.function.nnz_in(k) for k in moving]
        seeds = rng.standard_normal(sum(sizes))
        split = np.split(seeds, np.cumsum(sizes)[:-1])
        symbols = [ca.SX.sym(n, e.function.nnz_in(k)) for k, n in enumerate(e.inputs)]
        jac = ca.Function("j", symbols, [ca.jacobian(e.function(*symbols), ca.vertcat(
            *(symbols[k] for k in moving)))])
        matrix = np.array(jac(*args), dtype=float)
        got = np.array(e.derivative(*args, *split), dtype=float).ravel()
        scale = np.abs(matrix) @ np.abs(seeds)
        assert np.all(np.abs(got - matrix @ seeds) <= 1e-12 * np.maximum(scale, 1e-300)), \
            e.name


# ---- the examples that need no MSL ------------------------------------------------------------

def _load_example(roots, name):
    """An example of the built library, loaded through a model outside the library's root
    (rumoca 0.10 resolves a file inside a root without the other roots)."""
    session = rumoca.Session(roots=[str(r) for r in roots])
    return session.loads(f"model Run\n  extends {ROOT}.{reference.class_path(name)};\nend Run;\n",
                         model="Run")


def _experiment(built, name: str) -> dict[str, float]:
    """The example ``name``'s experiment annotation as the library writes it."""
    text = (built / ROOT / f"{reference.class_path(name).replace('.', '/')}.mo").read_text(
        encoding="utf-8")
    found = re.search(r"experiment\(([^)]*)\)", text)
    assert found, name
    return {k: float(v) for k, v in re.findall(r"(\w+)=([^,\s]+)", found.group(1))}


def _own_tolerance(built, *names: str):
    """rumoca's settings at the examples' own experiment tolerance (one for all of ``names``):
    relative the annotation's, absolute reference.ABSOLUTE_SHARE of it."""
    tolerances = {_experiment(built, n)["Tolerance"] for n in names}
    assert len(tolerances) == 1, names
    (tolerance,) = tolerances
    return rumoca.SimConfig(solver="rk-like", rtol=tolerance,
                            atol=tolerance * reference.ABSOLUTE_SHARE)


def test_every_example_has_a_reference_compared_on_its_signals(built):
    """MSL's regression layout: each example with an experiment annotation has its CSV and
    comparisonSignals.txt (time first, every signal a column of the CSV) in
    Resources/Reference/WheelTerrain/<the example's class path>/, and its run stops at the
    CSV's end."""
    examples = [p.stem for p in (built / ROOT / "Examples").rglob("*.mo")
                if "experiment(" in p.read_text(encoding="utf-8")]
    # SteadyC2, SlipRamp, 5 rovers, RigC1 ... RigC4, PlanarRig, PlanarRover, PlanarRoverSlope
    assert len(examples) == 14
    for name in examples:
        signals = reference.read_signals(built, name)
        ref = reference.read(built, name)
        assert signals[0] == "time"
        assert set(signals) <= set(ref), name
        run = _experiment(built, name)
        assert ref["time"][-1] == pytest.approx(run["StopTime"], abs=1e-12), name
        assert run["Tolerance"] == reference.tolerance(name)


@pytest.fixture(scope="module")
def quasi_static(built, msl_root):
    """SteadyC2 and SlipRamp side by side in one rumoca model (the quasi-static contact
    compiled once), run over SlipRamp's second."""
    model = rumoca.Session(roots=[str(msl_root)]).loads(
        f"model Run\n  {ROOT}.Examples.SteadyC2 c2;\n  {ROOT}.Examples.SlipRamp ramp;\n"
        f"  {ROOT}.Components.QuasiStaticWheel side(load=62, slip=0.2, slipAngle=0.3, "
        "turnSlip=2);\n"
        f"  {ROOT}.Components.Wheel w(sinkage=0.012, sinkageRate=0, wheelSpeed=0.25, "
        "carriageSpeed=0.02, slipAngle=-0.2, yawRate=0.04);\n"
        f"  {ROOT}.Components.Wheel back(sinkage=0.012, sinkageRate=0, wheelSpeed=-0.25, "
        "carriageSpeed=-0.02, slipAngle=0.2, yawRate=-0.04);\n"
        f"  {ROOT}.Components.Wheel record_(redeclare {ROOT}.Records.Presets.PaperTable1 "
        "parameters, sinkage=0.012, sinkageRate=0, wheelSpeed=0.25, carriageSpeed=0.02, "
        "slipAngle=0, yawRate=0);\n"
        f"  {ROOT}.Components.Wheel vector(p={ROOT}.Data.paperTable1, sinkage=0.012, "
        "sinkageRate=0, wheelSpeed=0.25, carriageSpeed=0.02, slipAngle=0, yawRate=0);\n"
        "end Run;\n", model="Run")
    assert model.structure().is_balanced
    return model.simulate((0.0, 1.0), dt=0.05,
                          config=_own_tolerance(built, "SteadyC2", "SlipRamp"))


@needs_msl
@pytest.mark.slow
def test_steady_c2_matches_the_steady_state(built, quasi_static):
    expected = api.steady_state(presets.load(), 62.0, 0.25, slip_definition="paper")
    ref = reference.read(built, "SteadyC2")
    for key in ("sinkage", "drawbar_pull", "torque"):
        assert ref[named(key)][0] == expected[key]
        got = quasi_static[named(f"c2.{key}")][-1]
        assert abs(got - expected[key]) <= 1e-8 * abs(expected[key]), key


@needs_msl
@pytest.mark.slow
def test_a_wheel_takes_its_parameters_as_a_preset_record_or_as_a_vector(quasi_static):
    """Components.Wheel with a preset redeclared as its ``parameters`` record (PaperTable1) is
    the Wheel given that preset's vector (Data.paperTable1) as ``p``, bit for bit (the
    default record, RashidPatch, has other soil values: measured -14.8 N against -13.0 N)."""
    assert not np.array_equal(presets.load("paper-table1").vector(), presets.load().vector())
    for key in ("normal_force", "drawbar_pull", "torque", "plastic_sinkage"):
        assert np.array_equal(quasi_static[named(f"record_.{key}")],
                              quasi_static[named(f"vector.{key}")]), key


@needs_msl
@pytest.mark.slow
def test_the_wheels_at_a_slip_angle_give_the_models_side_force(quasi_static):
    """QuasiStaticWheel at a slip angle and a turn slip: the steady state's lateral force and
    moments (its sinkage solved by the tool, 1e-8); Wheel (the soil with memory, its plastic
    sinkage still 0 at the start, so pressing) at a yaw rate (turn slip 2 rad/m):
    build().lateral_memory at its state, bit for bit (the turning moment within 1e-10)."""
    steady = api.steady_state(presets.load(), 62.0, 0.2, slip_angle=0.3, turn_slip=2.0)
    for key in ("lateral_force", "aligning_moment", "turning_moment"):
        got = quasi_static[named(f"side.{key}")][-1]
        assert abs(got - steady[key]) <= 1e-8 * abs(steady[key]), key
    assert steady["lateral_force"] < 0
    p = presets.load().vector()
    fns = model_functions.build()
    slip = quasi_static["w.slip"][0]
    pressure = quasi_static[f"w.y[{contact.CONTACT_OUTPUTS.index('mean_pressure') + 1}]"][0]
    want = np.array(fns.lateral_memory(0.012, slip, -0.2, 0.04 / 0.02, 0.0, pressure,
                                       p)).ravel()
    assert quasi_static["w.lateralForce"][0] == want[0]
    assert quasi_static["w.aligningMoment"][0] == want[1]
    turning = contact.LATERAL_OUTPUTS.index("turning_moment")
    # the patch's width moment runs through expm1, which the library writes as its series or
    # exp(x) - 1 (translate.SUBSTITUTED): within 1e-10, not bit for bit
    assert quasi_static["w.turningMoment"][0] == pytest.approx(want[turning], rel=1e-10)
    assert want[turning] != want[1]
    assert want[0] > 0  # moving toward its right: pushed to its left


@needs_msl
@pytest.mark.slow
def test_the_wheel_rolling_backward_is_the_mirror_image_of_the_wheel_rolling_forward(
        quasi_static):
    """Wheel at (-omega, -V) with the slip angle and yaw rate negated (a reflection x -> -x):
    the forward wheel's outputs at the start, those along x and about the vertical negated,
    bit for bit (the FMU's MIRRORED)."""
    for key, sign in (("normal_force", 1), ("drawbar_pull", -1), ("torque", -1), ("slip", 1),
                      ("rut_left", 1), ("lateral_force", 1), ("aligning_moment", -1),
                      ("turning_moment", -1), ("overturning_moment", 1)):
        forward, back = quasi_static[named(f"w.{key}")][0], quasi_static[named(f"back.{key}")][0]
        assert back == sign * forward, (key, forward, back)
    assert quasi_static["w.drawbarPull"][0] != 0
    assert quasi_static["back.rolling"][0] == -1


@needs_msl
@pytest.mark.slow
def test_a_slip_ramp_of_the_quasi_static_wheel_matches_the_steady_state(built, quasi_static):
    ref = reference.read(built, "SlipRamp")
    assert np.allclose(np.asarray(quasi_static.time), ref["time"], rtol=0, atol=1e-12)
    for key in reference.read_signals(built, "SlipRamp")[1:]:
        got = np.asarray(quasi_static[f"ramp.{key}"])
        assert np.all(np.abs(got - ref[key]) <= 1e-8 * np.abs(ref[key]) + 1e-12), key
    assert ref["slip"][0] == reference.RAMP[0]
    assert ref["drawbarPull"][0] < 0 < ref["drawbarPull"][-1]  # braking to driving


ROVER_GROUPS = {"level-slope-descent-pull": ("Rover", "RoverSlope", "RoverDescent",
                                             "RoverPullTest"),
                "soft-patch": ("RoverSoftPatch",)}
"""The rover examples, compared over their whole run in groups of the same run (one rumoca
model holding each group's examples side by side: the contact functions are compiled once).
The slope ramps from 3 s to 8 s and 5.5 s, the holding force rises all along, the soft patch
lies under the front axle from 9.4 s to 19.0 s, under the rear from 22.1 s to 31.7 s."""
ROVER_CHECKED = tuple(e for group in ROVER_GROUPS.values() for e in group)
ROVER_FIRST_SECOND = ("Rover",)
"""Compared over its first second only: on level ground the pulls settle to ~1e-3 N, so 1e-8 of
their largest value (0.06 N, in the first second) is 6e-10 N, below rumoca's error where its
steps cross the contact's switches over 10 s (1.4e-9 N, as in the other examples)."""


PATCH_EXIT = pytest.mark.xfail(strict=True, reason=(
    "with the imprint relaxing toward the soil ahead (model.imprint_relaxation 1, the default "
    "since 2026-11-28) the rear wheels leaving the soft patch (31.7 s) are hard for both "
    "integrators: rumoca at the example's 1e-13 is 5.2e-8 of the largest pull from the CVODES "
    "reference at the sample after it (1e-11 elsewhere; rumoca refuses 1e-14), CVODES at 1e-13 "
    "does not get past 31.756 s in 1e7 steps; with 0 the group met 1e-8"))


@needs_msl
@pytest.mark.slow
@pytest.mark.parametrize("group", [
    g if g != "soft-patch" else pytest.param(g, marks=PATCH_EXIT) for g in ROVER_GROUPS])
def test_the_rover_of_four_wheels_follows_the_python_models_trajectory(built, msl_root, group):
    """Examples.FMUTwin.Rover (over its first second), RoverSlope, RoverDescent, RoverPullTest and
    RoverSoftPatch (RoverChassis and four Wheels or MapWheels) against the Python
    model's rover in model exchange (the RoverChassis FMU's rates on four contacts with memory,
    CVODES at 1e-12), on each example's comparisonSignals.txt: 1e-8 of each signal's largest
    value. rumoca at the examples' own experiment tolerance, 1e-13 (absolute 1e-15): the
    contact switches (the soil's memory yielding or unloading, the ripple's
    clip) are not events, and rumoca's error where its steps cross them falls with its
    tolerance (measured against the reference, worst quantity over the descent: 2.7e-8 N in a
    pull at 1e-12, 3.7e-9 N at 1e-13; the rumoca runs at the two tolerances differ by the same
    2.7e-8 N, so it is rumoca's error, not CVODES')."""
    examples = ROVER_GROUPS[group]
    runs = {reference.rover_run(e) for e in examples}
    assert len(runs) == 1
    ((stop, interval),) = runs
    parts = "".join(f"  {ROOT}.{reference.class_path(e)} e{k};\n"
                    for k, e in enumerate(examples))
    model = rumoca.Session(roots=[str(msl_root)]).loads(f"model Run\n{parts}end Run;\n",
                                                        model="Run")
    assert model.structure().is_balanced
    result = model.simulate((0.0, stop), dt=interval, config=_own_tolerance(built, *examples))
    # the output grid (the soft patch's edges are events: rumoca adds a row at each)
    time = np.asarray(result.time)
    grid = np.flatnonzero(np.abs(time / interval - np.round(time / interval)) < 1e-9)
    for k, example in enumerate(examples):
        n = round((1.0 if example in ROVER_FIRST_SECOND else stop) / interval) + 1
        ref = reference.read(built, example)
        assert np.allclose(time[grid][:n], ref["time"][:n], rtol=0, atol=1e-9)
        for key in reference.read_signals(built, example)[1:]:
            got, want = np.asarray(result[f"e{k}.{key}"])[grid][:n], ref[key][:n]
            assert np.max(np.abs(got - want)) <= 1e-8 * np.max(np.abs(want)), (example, key)


@needs_msl
@pytest.mark.slow
def test_the_rover_examples_climb_descend_and_pull_as_their_profiles_say(built):
    """The examples' references over their last 2 s: the wheels' pulls carry the weight's
    share along the slope (10 deg up, 5 deg down) or the holding force (1 N/s), within 1 %;
    on level ground they stay near zero."""
    weight = 10.0 * 9.81
    for example in ROVER_CHECKED:
        ref = reference.read(built, example)
        late = ref["time"] >= 8.0
        if example == "RoverSoftPatch":  # each axle sinks deeper on the patch than before it
            for wheel, on in (("front_left", (12.0, 18.5)), ("rear_left", (25.0, 31.5))):
                sinkage = ref[named(f"{wheel}.sinkage")]
                before = np.mean(sinkage[(ref["time"] >= 6) & (ref["time"] < 9)])
                patch = np.mean(sinkage[(ref["time"] >= on[0])
                                                        & (ref["time"] < on[1])])
                assert patch > before + 2e-3, (wheel, before, patch)
        pull = sum(np.mean(ref[named(f"{w}.drawbar_pull")][late]) for w in
                   ("front_left", "front_right", "rear_left", "rear_right"))
        expected = {"Rover": 0.0, "RoverSoftPatch": 0.0,
                    "RoverSlope": weight * math.sin(math.radians(10.0)),
                    "RoverDescent": -weight * math.sin(math.radians(5.0)),
                    "RoverPullTest": 1.0 * np.mean(ref["time"][late])}[example]
        assert abs(pull - expected) <= 0.01 * max(abs(expected), 2.0), (example, pull)


@needs_msl
@pytest.mark.slow
def test_a_wheel_running_the_external_contact_is_balanced_and_refused_by_name(msl_root):
    """Redeclared to Functions.External.contact, the Wheel is plug-compatible (rumoca flattens
    it and finds it balanced); rumoca cannot execute external C and says so, naming the C
    function (the C itself: tests/test_modelica_external.py)."""
    session = rumoca.Session(roots=[str(msl_root)])
    model = session.loads(
        f"model Run\n  {ROOT}.Components.Wheel w(redeclare function contactFunction = "
        f"{ROOT}.Functions.External.contact, sinkage=0.01, sinkageRate=0, wheelSpeed=0.1, "
        "carriageSpeed=0.01, slipAngle=0, yawRate=0);\nend Run;\n", model="Run")
    assert model.structure().is_balanced
    with pytest.raises(Exception, match=r"WheelTerrain_contactCase.*cannot execute"):
        model.simulate((0.0, 0.1), dt=0.05)


# ---- with the Modelica Standard Library --------------------------------------------------------

@needs_msl
def test_every_quantity_of_the_records_is_an_msl_si_type():
    units = (reference.find_msl() / "Modelica" / "Units.mo").read_text(encoding="utf-8")
    si = set(re.findall(r"^\s*type (\w+)\s*=", units, re.M))
    from wheelterrain.parameters import TABLE

    assert {row.quantity for row in TABLE if row.quantity} <= si


@needs_msl
@pytest.mark.slow
def test_the_rig_on_msl_components_follows_the_python_models_trajectory(built, msl_root):
    """Rig (Components.Contact on MSL flanges, an MSL speed loop, carriage and mass) against
    the Python model's continuous-time rig (RigC1 ... RigC4's references and signals) over
    the first second of each case: 1e-8 relative (rumoca at the examples' own 1e-12: at 1e-10
    its step across the plastic
    sinkage's yield, where the wheel first presses the soil, leaves 1.3e-8 of the plastic
    sinkage at C1)."""
    model = _load_example([msl_root], "Rig")
    structure = model.structure()
    assert structure.is_balanced
    config = _own_tolerance(built, *(f"Rig{case}" for case in reference.RIG_CASES))
    for case, slip_paper in reference.RIG_CASES.items():
        result = model.simulate((0.0, 1.0), dt=reference.RIG_INTERVAL,
                                params={"slipPaper": slip_paper}, config=config)
        ref = reference.read(built, f"Rig{case}")
        n = len(result.time)
        assert n == 101
        for key in reference.read_signals(built, f"Rig{case}")[1:]:
            got, want = np.asarray(result[key]), ref[key][:n]
            scale = np.max(np.abs(want))
            assert np.max(np.abs(got - want)) <= 1e-8 * scale, (case, key)


# ---- the component layer: Terrain and Wheels.PlanarWheel (MSL and PlanarMechanics) -------------

needs_planar = pytest.mark.skipif(
    reference.find_msl() is None or not (reference.find_msl() / "PlanarMechanics").is_dir(),
    reason="needs MSL 4.x and PlanarMechanics 1.6 side by side on MODELICAPATH (the shared "
           "archive unpacks both)")


@needs_planar
def test_the_terrains_shapes_and_soil_are_the_interpolation_and_the_map(msl_root):
    """Terrain.height and slopeAt on a profile against numpy's interpolation (level beyond the
    table), on a plane and flat; Terrain.soil with a patch against the Terrain FMU's map
    (ground.soil_at)."""
    from wheelterrain.model import ground

    table = [[-0.5, 0.02], [0.0, 0.0], [0.4, 0.1], [1.0, 0.1], [1.3, -0.05]]
    values = ground.defaults() | {"patch.start": 0.3, "patch.end": 0.9,
                                  **{f"patch.{k.split('.')[1]}": v for k, v in
                                     ground.soft_patch(presets.load()).items()}}
    g = "{" + ", ".join(repr(float(values[n])) for n in ground.NAMES) + "}"
    rows = "{" + ", ".join(f"{{{x!r}, {h!r}}}" for x, h in table) + "}"
    model = rumoca.Session(roots=[str(msl_root)]).loads(
        "model Run\n"
        f"  inner {ROOT}.Terrain terrain(ground={ROOT}.Types.Ground.profile, profile={rows}, "
        f"g={g});\n"
        f"  {ROOT}.Terrain plane(ground={ROOT}.Types.Ground.plane, slope=0.2);\n"
        f"  {ROOT}.Terrain flat;\n"
        "  Real x = -1 + time;\n"
        "  Real h = terrain.height(x);\n  Real a = terrain.slopeAt(x);\n"
        f"  Real soil[{len(ground.SOIL_NAMES)}] = terrain.soil(x);\n"
        "  Real h_plane = plane.height(x);\n  Real a_plane = plane.slopeAt(x);\n"
        "  Real h_flat = flat.height(x);\nend Run;\n", model="Run")
    result = model.simulate((0.0, 3.0), dt=0.0125)
    x = np.asarray(result["x"])
    xs, hs = np.array(table).T
    assert np.allclose(result["h"], np.interp(x, xs, hs), rtol=0, atol=1e-15)
    segment = np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 2)
    slopes = np.arctan(np.diff(hs) / np.diff(xs))[segment]
    inside = (x > xs[0]) & (x < xs[-1])
    assert np.allclose(result["a"], np.where(inside, slopes, 0.0), rtol=0, atol=1e-15)
    assert np.any(result["a"] < 0)
    assert np.any(result["a"] > 0)
    assert np.allclose(result["h_plane"], x * math.tan(0.2), rtol=0, atol=1e-15)
    assert np.all(np.asarray(result["a_plane"]) == 0.2)
    assert np.all(np.asarray(result["h_flat"]) == 0)
    params = {n: values[n] for n in ground.NAMES}
    for k, xk in enumerate(x[::8]):
        want = [float(v) for v in ground.soil_at(float(xk), params)]
        got = [result[f"soil[{j + 1}]"][8 * k] for j in range(len(want))]
        assert got == want, xk


@pytest.fixture(scope="module")
def planar_rig(msl_root):
    """Examples.PlanarRig compiled once (its slip, inclination, speed and start are parameters
    rumoca changes between runs)."""
    model = _load_example([msl_root], "PlanarRig")
    assert model.structure().is_balanced
    return model


@needs_planar
@pytest.mark.slow
@pytest.mark.parametrize("angle_deg", [0.0, 15.0])
def test_the_planar_wheel_on_its_rig_is_the_rig_level_and_tilted(built, planar_rig, angle_deg):
    """Examples.PlanarRig (a PlanarWheel on PlanarMechanics' Frame, an inner Terrain, an MSL
    speed loop) against the Python model's rig (RigC1 ... RigC4's references, the rig on
    Components.Contact checks the same files) on PlanarRig's comparisonSignals.txt over the
    first second of each case, at its own experiment tolerance: 1e-8 of each signal's largest
    value (measured: 1.1e-9 at worst, the plastic sinkage tilted at C4). Tilted
    by 15 deg (terrain plane and carriage guide together, the load along the normal) the
    trajectory in the terrain's frame is the level one: the sinkage from the hub's clearance,
    the speeds along the terrain, the forces turned into the world frame and back."""
    config = _own_tolerance(built, "PlanarRig")
    for case, slip_paper in reference.RIG_CASES.items():
        result = planar_rig.simulate((0.0, 1.0), dt=reference.RIG_INTERVAL, config=config,
                                     params={"slipPaper": slip_paper,
                                             "angle": math.radians(angle_deg)})
        ref = reference.read(built, f"Rig{case}")
        n = len(result.time)
        assert n == 101
        for key in reference.read_signals(built, "PlanarRig")[1:]:
            got, want = np.asarray(result[key]), ref[key][:n]
            assert np.max(np.abs(got - want)) <= 1e-8 * np.max(np.abs(want)), (case, key)


@needs_planar
@pytest.mark.slow
def test_the_planar_wheel_rolls_backward_as_the_mirror_and_lands_from_above(planar_rig):
    """The rig run backward (rim and carriage speeds negated): the forward run's sinkage and
    normal force, its pull and wheel speed negated (the FMU's mirror, through PlanarWheel's
    frames); dropped from 2 mm above the soil the wheel falls, lands and carries the load (the
    soil's memory out of the soil stays at the surface: before, its rate was -1e295 m/s there)."""
    config = rumoca.SimConfig(solver="rk-like", rtol=1e-10, atol=1e-12)
    runs, rim_speed = {}, rig.defaults()["rig.rim_speed"]
    for sign in (1, -1):
        runs[sign] = planar_rig.simulate((0.0, 1.0), dt=reference.RIG_INTERVAL, config=config,
                                         params={"slipPaper": 0.25,
                                                 "rimSpeed": sign * rim_speed})
    for key, sign in (("sinkage", 1), ("normal_force", 1), ("drawbar_pull", -1),
                      ("drive.inertia.w", -1), ("wheel.plastic_sinkage", 1)):
        forward, back = np.asarray(runs[1][named(key)]), np.asarray(runs[-1][named(key)])
        assert np.max(np.abs(back - sign * forward)) <= 1e-9 * np.max(np.abs(forward)), key
    assert np.all(np.asarray(runs[-1]["wheel.contact.rolling"])[1:] == -1)
    dropped = planar_rig.simulate((0.0, 0.5), dt=0.0005, config=rumoca.SimConfig(
        solver="rk-like", rtol=1e-8, atol=1e-10), params={"slipPaper": 0.25,
                                                          "sinkage_start": -0.002})
    sinkage = np.asarray(dropped["sinkage"])
    air = sinkage < 0
    assert air[0]
    assert not air[-1]
    assert np.all(np.asarray(dropped["normalForce"])[air] == 0)
    assert np.all(np.asarray(dropped["wheel.plasticSinkage"])[air] == 0)
    load = rig.defaults()["rig.load"]
    assert abs(np.mean(np.asarray(dropped["normalForce"])[-100:]) - load) < 0.05 * load


@needs_planar
@pytest.mark.slow
def test_the_rover_from_standard_parts_is_the_python_rover(built, msl_root):
    """Examples.PlanarRoverSlope (PlanarRover: a body on PlanarMechanics' Frame, two
    FixedTranslation axles, four PlanarWheels, four speed-loop drives from MSL parts mounted on
    the wheels' supports, only connections between them) against RoverSlope's reference, the
    Python model's rover: 3 s on level ground from its start in the soil, then the climb to
    10 deg. At its own experiment tolerance every compared signal within 1e-8 of its largest
    value (measured 1.3e-10, a front wheel's pull; PlanarRover against Rover's 10 s 2.1e-9). The
    chassis pitches (the motors' reactions and the load transfer), so the wheels' spin, the
    drives' mounting and the pitch rate in each axle's speed all take part."""
    model = _load_example([msl_root], "PlanarRoverSlope")
    assert model.structure().is_balanced
    stop, interval = reference.rover_run("RoverSlope")
    result = model.simulate((0.0, stop), dt=interval,
                            config=_own_tolerance(built, "PlanarRoverSlope"))
    ref = reference.read(built, "PlanarRoverSlope")
    assert ref.keys() == reference.read(built, "RoverSlope").keys()
    time = np.asarray(result.time)
    assert np.allclose(time, ref["time"], rtol=0, atol=1e-9)
    for key in reference.read_signals(built, "PlanarRoverSlope")[1:]:
        got, want = np.asarray(result[key]), ref[key]
        assert np.max(np.abs(got - want)) <= 1e-8 * np.max(np.abs(want)), key
    pitch = np.asarray(result["pitch"])
    assert np.ptp(pitch[time >= 3.0]) > 1e-3  # the climb pitches the chassis


@needs_planar
@pytest.mark.slow
def test_the_rover_from_standard_parts_stops_and_reverses(msl_root):
    """PlanarRover with its four drives' commands ramped from the rim speed (0.03 m/s) to its
    negative over 1-3 s: the rover stops and drives backward, through the wheels' regularised
    slip and their blend of the two directions of rolling within the slip's speed floor (the
    FMU's; turned at once, neither of rumoca's solvers passed the stop in 5 minutes). Every
    wheel's rolling turns once; backward the rover runs at its forward speed (the mirror image
    on level ground: measured 2.4e-6 apart, the imprints' histories differ)."""
    # literal values: rumoca 0.10 did not finish compiling rimSpeed_end=-rimSpeed (a
    # modifier naming the base's final parameter) in 20 minutes
    model = rumoca.Session(roots=[str(msl_root)]).loads(
        f"model Run\n  extends {ROOT}.Examples.PlanarRover(rimSpeed_end=-0.03, "
        "changeStartTime=1, changeDuration=2);\nend Run;\n", model="Run")
    assert model.structure().is_balanced
    result = model.simulate((0.0, 5.0), dt=0.01, config=rumoca.SimConfig(
        solver="rk-like", rtol=1e-6, atol=1e-9))
    time, speed = np.asarray(result.time), np.asarray(result["speed"])
    forward = speed[np.argmin(np.abs(time - 1.0))]
    assert forward > 0.03
    assert speed[-1] == pytest.approx(-forward, rel=1e-4)
    for wheel in ("front_left", "front_right", "rear_left", "rear_right"):
        rolling = np.asarray(result[named(f"{wheel}.contact.rolling")])
        assert rolling[0] == 1
        assert rolling[-1] == -1
        assert np.count_nonzero(np.diff(rolling)) == 1, wheel
        slip = np.asarray(result[named(f"{wheel}.slip")])
        assert np.all(np.abs(slip) <= 1)


HORIZONTAL_RUN = """model Run
  model Mover "a hub moved in the ground plane at a set speed, slip angle and yaw rate"
    parameter Real U = 0.03 "speed [m/s]";
    parameter Real beta = 0.2 "the velocity's angle from the heading [rad]";
    parameter Real yaw = 0.02 "the heading's yaw rate [rad/s]";
    parameter Real psi0 = 0.4 "the heading at the start [rad]";
    PlanarMechanics.Interfaces.Frame_b frame_b;
    Real x(start=0, fixed=true);
    Real y(start=0, fixed=true);
  equation
    frame_b.phi = psi0 + yaw*time;
    der(x) = U*cos(frame_b.phi + beta);
    der(y) = U*sin(frame_b.phi + beta);
    frame_b.x = x;
    frame_b.y = y;
  end Mover;
  parameter Real omega = 0.7 "the wheel's spin [rad/s]";
  Mover mover;
  WheelTerrain.Wheels.HorizontalWheel wheel;
  Modelica.Mechanics.Rotational.Sources.Speed drive(exact=true);
  Modelica.Blocks.Sources.Constant spin(k=omega);
  Modelica.Blocks.Sources.Constant weight(k=62);
equation
  connect(mover.frame_b, wheel.frame_a);
  connect(drive.flange, wheel.flange_a);
  connect(spin.y, drive.w_ref);
  connect(weight.y, wheel.load);
end Run;
"""


@needs_planar
@pytest.mark.slow
def test_the_horizontal_wheel_is_the_steady_state_at_its_hubs_slip_angle_and_yaw(msl_root,
                                                                                monkeypatch):
    """Wheels.HorizontalWheel under a hub moved (a body written on PlanarMechanics' Frame) at
    0.03 m/s, 0.2 rad from its heading, yawing at 0.02 rad/s, spun at 0.7 rad/s, 62 N: the
    steady state's drawbar pull, lateral force, turning moment and torque at that slip, slip
    angle and turn slip within 1e-8, the forces on the hub the pull and the side force turned
    by the heading; moved backward (speed and spin negated) the mirror image: the contact at
    slip angle and turn slip negated, pull, torque and turning moment negated back."""
    from wheelterrain.fmu import functions as fmu_functions

    # the model names MSL classes itself: rumoca 0.10 would take them from MODELICAPATH, a
    # second root, and then not resolve the library's classes from them (one root: msl_root)
    monkeypatch.delenv("MODELICAPATH", raising=False)
    model = rumoca.Session(roots=[str(msl_root)]).loads(HORIZONTAL_RUN, model="Run")
    assert model.structure().is_balanced
    config = rumoca.SimConfig(solver="rk-like", rtol=1e-10, atol=1e-12)
    params = presets.load()
    radius = float(fmu_functions.slip_radius(ca.DM(params.vector())))
    for sign in (1, -1):
        result = model.simulate((0.0, 1.0), dt=0.5, config=config,
                                params={"mover.U": sign * 0.03, "omega": sign * 0.7})
        speed, rim = 0.03 * math.cos(0.2), 0.7 * radius
        slip = (rim - speed) / max(rim, speed)
        steady = api.steady_state(params, 62.0, slip, "unified", slip_angle=sign * 0.2,
                                  turn_slip=sign * 0.02 / speed)
        want = {"slip": slip, "slip_angle": sign * 0.2, "lateral_force": steady["lateral_force"]}
        want.update({k: sign * steady[k] for k in ("drawbar_pull", "turning_moment", "torque")})
        for key, value in want.items():
            got = result[named(f"wheel.{key}")][-1]
            assert abs(got - value) <= 1e-8 * abs(value), (sign, key, got, value)
        heading = 0.4 + 0.02 * 1.0
        pull, side = want["drawbar_pull"], want["lateral_force"]
        fx = pull * math.cos(heading) - side * math.sin(heading)
        fy = pull * math.sin(heading) + side * math.cos(heading)
        assert result["mover.frame_b.fx"][-1] == pytest.approx(fx, rel=1e-8)
        assert result["mover.frame_b.fy"][-1] == pytest.approx(fy, rel=1e-8)
        assert result["mover.frame_b.t"][-1] == pytest.approx(want["turning_moment"], rel=1e-8)
    assert steady["lateral_force"] > 0  # moving toward its right (backward): pushed left


@needs_planar
@pytest.mark.slow
def test_the_horizontal_wheel_blends_the_two_directions_at_the_turn_of_rolling(msl_root,
                                                                              monkeypatch):
    """Wheels.HorizontalWheel driven straight (no slip angle, no yaw) at speeds within the
    slip's speed floor of the turn of rolling (omega*R + v = 0), forward and backward of it:
    the FMU's quasi-static blend of the wheel rolling either way (terrain_quasi_static, the
    same inputs), drawbar pull, torque and sinkage within 1e-8 (relative; of 1 N, 0.1 N*m and
    1 cm below those); where the two
    speeds are further apart it is the one direction's contact as before (the test above)."""
    from wheelterrain.fmu import functions as fmu_functions
    from wheelterrain.fmu import variables as fmu_variables

    monkeypatch.delenv("MODELICAPATH", raising=False)
    model = rumoca.Session(roots=[str(msl_root)]).loads(HORIZONTAL_RUN, model="Run")
    config = rumoca.SimConfig(solver="rk-like", rtol=1e-10, atol=1e-12)
    params = presets.load()
    radius = float(fmu_functions.slip_radius(ca.DM(params.vector())))
    quasi = fmu_functions.terrain_functions()[1]
    floor = fmu_functions.SLIP_SPEED_FLOOR
    shares = []
    for speed, rim in ((4e-6, -1e-6), (-1e-6, 0.5e-6), (2e-6, -2.5e-6), (-3e-6, -1e-6)):
        result = model.simulate((0.0, 0.5), dt=0.5, config=config, params={
            "mover.U": speed, "mover.beta": 0.0, "mover.yaw": 0.0, "omega": rim / radius})
        inputs = {n: 0.0 for n in fmu_variables.TERRAIN_INPUTS}
        inputs.update(load=62.0, wheel_speed=rim / radius, carriage_speed=speed)
        u = [inputs[n] for n in fmu_variables.TERRAIN_INPUTS]
        y, status, _ = quasi(u, params.vector(), 0.01)
        assert int(status) == fmu_functions.STATUS_OK
        want = dict(zip(fmu_variables.TERRAIN_OUTPUTS, y.full().ravel(), strict=True))
        for key, name, scale in (("drawbar_pull", "drawbar_pull", 1.0),
                                 ("torque", "torque", 0.1), ("sinkage", "contact_sinkage", 0.01)):
            got = result[named(f"wheel.{key}")][-1]
            assert abs(got - want[name]) <= 1e-8 * max(abs(want[name]), scale), (speed, key)
        shares.append(result["wheel.share"][-1])
        assert abs(rim + speed) < floor
    assert all(0 < share < 1 for share in shares)  # each point inside the blend


@needs_msl
def test_every_preset_record_gives_its_parameter_vector_options_as_enumerations(msl_root):
    """Records.parameterVector of every preset record (the options Types enumerations) is the
    preset's table vector (Data, the FMUs' and the CLI's), bit for bit: each option's literal
    turns into the table's code."""
    names = presets.available()
    parts = "".join(f"  parameter {ROOT}.Records.Presets.{library.preset_record(n)} r{k};\n"
                    f"  Real p{k}[{len(NAMES)}] = {ROOT}.Records.parameterVector(r{k});\n"
                    for k, n in enumerate(names))
    model = rumoca.Session(roots=[str(msl_root)]).loads(f"model Run\n{parts}end Run;\n",
                                                         model="Run")
    result = model.simulate((0.0, 1.0), dt=1.0)
    codes = set()
    for k, name in enumerate(names):
        want = presets.load(name).vector()
        got = [result[f"p{k}[{j + 1}]"][0] for j in range(len(NAMES))]
        assert got == [float(v) for v in want], name
        codes.add(want[NAMES.index("model.contact_form")])
    assert codes == {0.0, 1.0}  # both literals of an enumeration are met
    text = (msl_root / ROOT / "Records" / "Options.mo").read_text(encoding="utf-8")
    assert f"{ROOT}.Types.ContactForm contactForm" in text
