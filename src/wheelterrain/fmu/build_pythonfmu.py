"""Build the pythonfmu FMUs (WheelTerrain, SingleWheelRig, RoverChassis, Terrain), then make
their modelDescription.xml what a Modelica-minded FMI importer expects.

pythonfmu 0.7 writes no units, types, ranges or dependencies (upstream issues #33, #193). After its
build, :func:`finish_model_description` rewrites modelDescription.xml inside the FMU from the
same :class:`wheelterrain.fmu.variables.Var` lists the slaves register
(:func:`wheelterrain.fmu.description.describe`), puts the guard library in front of pythonfmu's
(:mod:`wheelterrain.fmu.build_guard`) and removes pythonfmu's exit crash from its binary.

The wheelterrain package itself is bundled into resources/, so the FMU needs only numpy and
casadi in the host's Python.
"""

from __future__ import annotations

import shutil
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path
from xml.etree import ElementTree as ET

from wheelterrain import compiled as native
from wheelterrain.files import replacing
from wheelterrain.fmu import build_guard
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.fmu.description import describe, pretty
from wheelterrain.fmu.toolchain import PACKAGE_DIR, SLAVE_SCRIPTS, BuildError, source_dir
from wheelterrain.fmu.variables import VARIABLES


def build(out: Path, models: tuple[str, ...] = tuple(SLAVE_SCRIPTS),
          compiled: bool = True,
          say: Callable[[str], None] = lambda message: None) -> list[Path]:
    """Build the pythonfmu FMUs into ``out``; returns their paths. ``say(message)`` is told as
    each FMU starts.

    ``compiled``: also generate WheelTerrain's Functions (:mod:`wheelterrain.fmu.functions`) as C,
    compile them and ship the libraries in its bundled package (``_compiled/*.so``), which the
    slave then calls instead of the CasADi VM. Without a C compiler the FMU is built without
    them (same results, slower); a compiler that fails is an error.
    """
    from pythonfmu.builder import FmuBuilder

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    built = []
    for name in models:
        say(f"building {name}.fmu (pythonfmu)")
        script = source_dir() / SLAVE_SCRIPTS[name]
        with tempfile.TemporaryDirectory(prefix="wheelterrain_build_") as tmp:
            staged = Path(tmp) / "wheelterrain"
            shutil.copytree(PACKAGE_DIR, staged,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "_compiled"))
            if compiled and name == "WheelTerrain" and native.compiler() is not None:
                try:
                    for fn in fmu_model.terrain_functions():
                        native.compile_function(fn, staged / "_compiled")
                except native.CompileError as err:
                    raise BuildError(str(err)) from err
            fmu = FmuBuilder.build_FMU(script, dest=tmp, project_files=[staged],
                                       canGetAndSetFMUstate=True, canSerializeFMUstate=True)
            finish_model_description(Path(fmu), name)
            target = out / f"{name}.fmu"
            with replacing(target) as partial:  # never a half-written FMU under the final name
                shutil.copyfile(fmu, partial)
        built.append(target)
    return built


# pythonfmu 0.7.0's Linux binary releases its interpreter state twice at process exit: a
# static std::shared_ptr<PyState> is destroyed by the C++ exit handlers, then the library's
# __attribute__((destructor)) finalizePythonInterpreter() assigns nullptr to that destroyed
# shared_ptr, which still holds the freed control block: a use after free that decrements
# (and may free again) freed memory. The heap is then corrupted and the host aborts at exit
# ("corrupted double-linked list", "pure virtual method called") in some runs, depending on
# what else freed memory (upstream note in fmu_src/README.md). The static destructor alone
# already destroys the state (on Windows DllMain runs first by the code's order: win64 is left);
# the fix turns the Linux destructor's call into a plain return, in our copy of the binary.
_EXIT_FIX_SYMBOL = b"finalizePythonInterpreter"
_ENDBR64 = bytes.fromhex("f30f1efa")
_EXIT_BUG_CODE = _ENDBR64 + bytes.fromhex("55660fefc0534883ec08488b2d")
"""The start of finalizePythonInterpreter as pythonfmu 0.7.0 ships it (reads the freed
shared_ptr); another start (a fixed pythonfmu) is left alone."""


def _symbol_offset(elf: bytes, symbol: bytes) -> int | None:
    """File offset of the code of dynamic ``symbol`` in a little-endian ELF64 library."""
    import struct

    if elf[:4] != b"\x7fELF" or elf[4] != 2 or elf[5] != 1:
        return None
    shoff, = struct.unpack_from("<Q", elf, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", elf, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", elf, shoff + k * shentsize)
                for k in range(shnum)]
    for _, kind, _, _, offset, size, link, _, _, entsize in sections:
        if kind != 11:  # SHT_DYNSYM
            continue
        names = sections[link][4]
        for entry in range(offset, offset + size, entsize):
            name, _, _, shndx, value, _ = struct.unpack_from("<IBBHQQ", elf, entry)
            end = elf.index(b"\0", names + name)
            if elf[names + name:end] == symbol and 0 < shndx < len(sections):
                addr, file_offset = sections[shndx][3], sections[shndx][4]
                return value - addr + file_offset
    return None


def fix_exit_crash(binary: bytes) -> bytes:
    """``binary`` (pythonfmu's Linux library) with the double release at exit removed: the
    destructor's call returns at once. Unchanged if the code is not the known-bad one."""
    at = _symbol_offset(binary, _EXIT_FIX_SYMBOL)
    if at is None or binary[at:at + len(_EXIT_BUG_CODE)] != _EXIT_BUG_CODE:
        return binary
    ret = at + len(_ENDBR64)
    return binary[:ret] + b"\xc3" + binary[ret + 1:]


def finish_model_description(fmu: Path, model: str) -> None:
    """Rewrite modelDescription.xml inside ``fmu`` (see the module docstring)."""
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        members = {info.filename: z.read(info.filename) for info in z.infolist()}
    describe(root, model, VARIABLES[model]())
    members["modelDescription.xml"] = pretty(root)
    for name in members:
        if name.startswith("binaries/linux64/") and name.endswith(".so"):
            members[name] = fix_exit_crash(members[name])
    _install_guard(members, model, root)
    with replacing(fmu) as partial, zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in members.items():
            z.writestr(name, data)


def _install_guard(members: dict[str, bytes], model: str, root: ET.Element) -> None:
    """Put the guard library (:mod:`wheelterrain.fmu.build_guard`) in front of pythonfmu's
    linux64 library: the guard becomes ``<model>.so``, pythonfmu's ``<model>_pythonfmu.so``.
    Without a C compiler the FMU keeps pythonfmu's library alone."""
    binary = f"binaries/linux64/{model}.so"
    guard = build_guard.guard_binary(model, root) if binary in members else None
    if guard is not None:
        members[f"binaries/linux64/{model}{build_guard.REAL_SUFFIX}.so"] = members[binary]
        members[binary] = guard
