"""WheelTerrain.Functions.External: the library's functions as CasADi-generated C behind
Modelica's external "C" interface. No Modelica tool here can link external C (rumoca evaluates
functions itself), so its C boundary is tested as a tool would call it:

- through ctypes on the linux64 shared library, with the argument types Modelica's external
  call passes (a double per scalar input, a pointer per array, the output by pointer): bit for
  bit the CasADi Function, at the points tests/test_modelica.py checks the generated functions at;
- a C host linked against the linux64 static archive (what a tool's linker does), and the same
  host cross-compiled and linked against the win64 DLL, run under Wine: the archive gives the
  shared library's numbers bit for bit, the DLL within 1e-12 relative (the Windows C runtime's
  libm differs from glibc's in the last bits);
- the Modelica side: every function of Functions has an External twin with the same
  declarations and derivative annotation, calling the C function the header declares; the
  components' replaceable contact functions are constrained by the dispatchers' signatures.
"""

from __future__ import annotations

import ctypes
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import modelica_points as mp
from wheelterrain import compiled, presets
from wheelterrain.fmu import build_native
from wheelterrain.modelica import external, library

WINE = shutil.which("wine") or shutil.which("wine64")
ROOT = library.LIBRARY
DOUBLE_P = ctypes.POINTER(ctypes.c_double)

pytestmark = pytest.mark.skipif(compiled.compiler() is None,
                                reason="needs a C compiler (.ci/run installs one)")


@pytest.fixture(scope="module")
def built(modelica_root) -> Path:
    """The library's folder WheelTerrain/, as `wheelterrain build --flavor modelica` writes it."""
    return modelica_root / library.LIBRARY


def _cases() -> list[tuple]:
    """(entry, arguments) for every function of Functions: the contact's and the slips' at
    every point (their derivatives where the contact has one, z > 0), the chassis' and the
    map's at every rover point; derivative seeds as tests/test_modelica.py's."""
    vectors = {name: presets.load(name).vector() for name in presets.available()}
    out = []
    for e in library.entries():
        base = [p for p in e.inputs if not p.name.startswith("der_")]
        seeds = [p for p in e.inputs if p.name.startswith("der_")]
        if {p.name for p in base} <= {*mp.COLUMN, "p"}:
            chosen = [(n, x) for n, x in mp.points() if x[0] > 0 or not seeds]
            for name, x in chosen:
                args = [vectors[name] if p.name == "p" else x[mp.COLUMN[p.name]] for p in base]
                args += [mp.SEED[mp.COLUMN[p.name[4:]]] for p in seeds]
                out.append((e, args))
        else:
            for pt in mp.rover_points():
                args = [pt[p.name] for p in base]
                args += [mp.vector_seed(p.name[4:], p.size) for p in seeds]
                out.append((e, args))
    return out


def _call(lib: ctypes.CDLL, entry, args) -> np.ndarray:
    f = getattr(lib, external.c_name(entry.name))
    f.restype = None
    arrays, c_args = [], []
    for port, value in zip(entry.inputs, args, strict=True):
        if port.size == 1:
            c_args.append(ctypes.c_double(float(np.ravel(value)[0])))
        else:
            arrays.append(np.ascontiguousarray(value, dtype=float))
            assert arrays[-1].size == port.size, port.name
            c_args.append(arrays[-1].ctypes.data_as(DOUBLE_P))
    outs = [np.full(port.size, np.nan) for port in entry.outputs]
    f(*c_args, *(o.ctypes.data_as(DOUBLE_P) for o in outs))
    return np.concatenate(outs)


def _reference(entry, args) -> np.ndarray:
    return np.array(entry.function(*args), dtype=float).ravel()


def test_through_ctypes_every_external_function_is_its_casadi_function_bit_for_bit(built):
    lib = ctypes.CDLL(str(built / "Resources/Library/linux64" / external.BINARIES["linux64"][1]))
    cases = _cases()
    names = {e.name for e, _ in cases}
    assert names == {e.name for e in library.entries()}
    assert len(cases) > 500
    for entry, args in cases:
        got, want = _call(lib, entry, args), _reference(entry, args)
        assert np.array_equal(got, want, equal_nan=True), (entry.name, got, want)


def _host_source() -> str:
    """A C host calling every WheelTerrain_* function: it reads lines 'name v1 v2 ...' (the
    inputs, arrays flattened) from the file argv[1] and prints the outputs, %.17g."""
    lines = ['#include <stdio.h>', '#include <string.h>', f'#include "{external.HEADER}"',
             "static double a[4096], y[4096];",
             "static int read(FILE* f, int n) { for (int k = 0; k < n; ++k)"
             " if (fscanf(f, \"%lf\", &a[k]) != 1) return 0; return 1; }",
             "int main(int argc, char** argv) {",
             "    char name[128]; int n = 0;",
             "    FILE* f = argc > 1 ? fopen(argv[1], \"r\") : NULL;",
             "    if (!f) return 2;",
             "    while (fscanf(f, \"%127s\", name) == 1) {",
             "        if (0) {"]
    for e in library.entries():
        count, offsets = 0, []
        for port in e.inputs:
            offsets.append(count)
            count += port.size
        args = [f"a[{o}]" if p.size == 1 else f"&a[{o}]"
                for p, o in zip(e.inputs, offsets, strict=True)]
        size = sum(p.size for p in e.outputs)
        lines += [f'        }} else if (!strcmp(name, "{e.name}")) {{',
                  f"            if (!read(f, {count})) return 3;",
                  f"            {external.c_name(e.name)}({', '.join(args)}, y);",
                  f"            n = {size};"]
    lines += ["        } else { return 4; }",
              '        for (int k = 0; k < n; ++k) printf("%.17g ", y[k]);',
              '        printf("\\n");', "    }", "    fclose(f);", "    return 0;", "}", ""]
    return "\n".join(lines)


def _script(cases) -> str:
    rows = []
    for entry, args in cases:
        values = np.concatenate([np.ravel(np.asarray(a, dtype=float)) for a in args])
        rows.append(entry.name + " " + " ".join(repr(float(v)) for v in values))
    return "\n".join(rows) + "\n"


def _read(text: str) -> list[np.ndarray]:
    return [np.array([float(v) for v in line.split()]) for line in text.splitlines()]


@pytest.fixture(scope="module")
def host(built, tmp_path_factory):
    folder = tmp_path_factory.mktemp("host")
    (folder / "host.c").write_text(_host_source())
    cases = _cases()
    (folder / "inputs.txt").write_text(_script(cases))
    return folder, cases


def test_a_host_linked_against_the_static_archive_gives_the_shared_librarys_numbers(built, host):
    folder, cases = host
    archive = built / "Resources/Library/linux64" / external.BINARIES["linux64"][0]
    exe = folder / "host"
    subprocess.run([compiled.compiler(), "-O1", "-Wall", "-Werror", "-I",
                    str(built / "Resources/C-Sources"), str(folder / "host.c"), str(archive),
                    "-lm", "-o", str(exe)], check=True, capture_output=True)
    run = subprocess.run([str(exe), str(folder / "inputs.txt")], capture_output=True,
                         text=True, check=False)
    assert run.returncode == 0, run.stderr
    rows = _read(run.stdout)
    assert len(rows) == len(cases)
    lib = ctypes.CDLL(str(built / "Resources/Library/linux64" / external.BINARIES["linux64"][1]))
    for (entry, args), got in zip(cases, rows, strict=True):
        assert np.array_equal(got, _call(lib, entry, args), equal_nan=True), entry.name


@pytest.mark.slow
@pytest.mark.skipif(build_native.cross_compiler() is None or WINE is None,
                    reason="needs gcc-mingw-w64-x86-64 and wine (.ci/run installs them)")
def test_under_wine_the_win64_dll_gives_the_linux64_numbers(built, host, wine_prefix):
    folder, cases = host
    dll = built / "Resources/Library/win64" / external.BINARIES["win64"][0]
    shutil.copyfile(dll, folder / dll.name)  # found beside the executable
    exe = folder / "host.exe"
    subprocess.run([build_native.cross_compiler(), "-O1", "-Wall", "-Werror", "-I",
                    str(built / "Resources/C-Sources"), str(folder / "host.c"),
                    str(folder / dll.name), "-o", str(exe)], check=True, capture_output=True)
    env = {**os.environ, "WINEPREFIX": str(wine_prefix), "WINEDEBUG": "-all"}
    run = subprocess.run([WINE, str(exe), str(folder / "inputs.txt")], capture_output=True,
                         text=True, check=False, env=env, cwd=folder)
    assert run.returncode == 0, run.stderr[-2000:]
    rows = _read(run.stdout)
    assert len(rows) == len(cases)
    lib = ctypes.CDLL(str(built / "Resources/Library/linux64" / external.BINARIES["linux64"][1]))
    worst = 0.0
    for (entry, args), got in zip(cases, rows, strict=True):
        want = _call(lib, entry, args)
        assert np.array_equal(np.isnan(got), np.isnan(want)), entry.name
        finite = ~np.isnan(want)
        scale = np.maximum(np.abs(want[finite]), 1.0)
        worst = max(worst, float(np.max(np.abs(got[finite] - want[finite]) / scale,
                                        initial=0.0)))
    assert worst <= 1e-12, worst


def _declarations(path: Path) -> list[str]:
    return [line for line in path.read_text().splitlines()
            if line.startswith(("  input ", "  output "))]


def test_every_function_has_an_external_twin_with_its_signature_and_derivative(built):
    functions, external_ = built / "Functions", built / "Functions/External"
    header = (built / "Resources/C-Sources" / external.HEADER).read_text()
    names = [e.name for e in library.entries()] + ["contact", "contactDer", "quasiStatic",
                                                   "quasiStaticDer"]
    listed = (external_ / "package.order").read_text().split()
    assert sorted(listed) == sorted(names)
    for name in names:
        twin = (external_ / f"{name}.mo").read_text()
        assert _declarations(external_ / f"{name}.mo") == _declarations(
            functions / f"{name}.mo"), name
        derivative = re.findall(r"derivative[^=]*=\w+", (functions / f"{name}.mo").read_text())
        assert re.findall(r"derivative[^=]*=\w+", twin) == derivative, name
        if name in ("contact", "contactDer", "quasiStatic", "quasiStaticDer"):
            continue  # the dispatchers: Modelica calling the External kernels
        call = re.search(r'external "C" (\w+)\(', twin)
        assert call is not None, name
        assert call.group(1) == external.c_name(name), name
        assert f" {external.c_name(name)}(" in header, name
    for stem in ("contact", "quasiStatic"):
        interface = built / "Functions/Interfaces" / f"{stem[0].upper()}{stem[1:]}.mo"
        assert _declarations(interface) == _declarations(functions / f"{stem}.mo")


def test_the_components_contact_function_is_replaceable_by_the_external_one(built):
    for component, stem in (("Contact", "contact"), ("PartialWheel", "contact"),
                            ("QuasiStaticWheel", "quasiStatic")):
        text = (built / "Components" / f"{component}.mo").read_text()
        interface = f"{stem[0].upper()}{stem[1:]}"
        assert (f"replaceable function {stem}Function = {ROOT}.Functions.{stem}\n"
                f"    constrainedby {ROOT}.Functions.Interfaces.{interface}") in text
        assert f"{ROOT}.Functions.{stem}(" not in text  # every call goes through it
        assert f"= {stem}Function(" in text
