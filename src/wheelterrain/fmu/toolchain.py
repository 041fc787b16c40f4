"""What every FMU build needs below the builders: the build's error, where the FMU sources
(fmu_src/) and the FMI headers are, the compilers (the native one is
:func:`wheelterrain.compiled.compiler`; the win64 cross compiler here), and C literals for the
generated headers. Imported by the pythonfmu, native and guard builds and the Modelica
library's external C (:mod:`wheelterrain.modelica.external`); imports none of them."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1]  # the wheelterrain package, bundled whole
REPO_DIR = PACKAGE_DIR.parents[1]
SLAVE_SCRIPTS = {"WheelTerrain": "wheelterrain_slave_terrain.py",
                 "SingleWheelRig": "wheelterrain_slave_rig.py",
                 "RoverChassis": "wheelterrain_slave_rover.py",
                 "Terrain": "wheelterrain_slave_ground.py"}
"""The pythonfmu slave script of each FMU (fmu_src/; unique module names, pythonfmu #228)."""
WIN64_CC = "x86_64-w64-mingw32-gcc"
"""The MinGW-w64 cross compiler (Debian: gcc-mingw-w64-x86-64) that builds binaries/win64."""


class BuildError(RuntimeError):
    """The FMU could not be built; the message says why."""


def source_dir() -> Path:
    """fmu_src/: inside the installed package (wheelterrain/fmu_src), else the checkout's."""
    for path in (PACKAGE_DIR / "fmu_src", REPO_DIR / "fmu_src"):
        if (path / SLAVE_SCRIPTS["WheelTerrain"]).is_file():
            return path
    raise BuildError(f"slave scripts not found in {PACKAGE_DIR / 'fmu_src'} or "
                     f"{REPO_DIR / 'fmu_src'}: the installation is incomplete (reinstall "
                     "wheelterrain)")


def fmi_headers() -> Path:
    """The FMI 2 and 3 headers, as they ship inside fmpy (fmpy/c-code)."""
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    if not (path / "fmi2Functions.h").is_file():
        raise BuildError(f"FMI 2 headers not found in {path} (they ship with fmpy)")
    return path


def cross_compiler() -> str | None:
    """The win64 cross compiler ($WHEELTERRAIN_WIN64_CC, else WIN64_CC on PATH), or None (the
    FMUs are then built for linux64 only)."""
    return os.environ.get("WHEELTERRAIN_WIN64_CC") or shutil.which(WIN64_CC)


def c_string(text: str) -> str:
    """``text`` as a C string literal."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def c_double(x: float) -> str:
    """``x`` as a C double literal that reads back exactly (INFINITY for infinities)."""
    if x == float("inf"):
        return "INFINITY"
    if x == float("-inf"):
        return "-INFINITY"
    return repr(float(x))
