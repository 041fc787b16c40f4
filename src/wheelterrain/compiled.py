"""CasADi Functions as generated C, compiled with the machine's C compiler and called through
ctypes with preallocated buffers.

Calling a CasADi Function from Python costs ~30 us of argument conversion before any arithmetic;
the same Function generated as C and called here costs ~1 us plus its arithmetic. The pythonfmu
WheelTerrain slave uses this when its build could compile the model (the compiled library ships
in the FMU's resources/ next to the bundled package); otherwise it falls back to the CasADi VM,
with identical results to rounding.

The generated C is CasADi's (``Function.generate``): no model is rewritten by hand.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from wheelterrain.files import locked, replacing

CFLAGS = ("-fPIC", "-shared")  # with the optimisation level compile_function is given


class CompileError(RuntimeError):
    """No C compiler, or the compiler failed; the message says which."""


def compiler() -> str | None:
    """The C compiler to use: $CC where it names a program that exists, else cc or gcc on
    PATH; None where there is none (a $CC that does not exist is none: the callers fall back to
    CasADi's VM, as without a compiler)."""
    chosen = os.environ.get("CC")
    if chosen:
        return chosen if shutil.which(chosen) else None
    return shutil.which("cc") or shutil.which("gcc")


def no_compiler_reason() -> str:
    """Why :func:`compiler` found none, for an error message."""
    chosen = os.environ.get("CC")
    if chosen:
        return f"no C compiler: $CC is {chosen!r}, which names no program"
    return "no C compiler (cc/gcc, or $CC) on PATH"


def cache_directory() -> Path:
    """Where libraries compiled at run time are kept between runs ($WHEELTERRAIN_CACHE, else
    the user's cache directory)."""
    root = os.environ.get("WHEELTERRAIN_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "wheelterrain")
    return Path(root)


def compile_function(fn: ca.Function, out_dir: Path, jacobian: bool = False,
                     optimisation: str = "-O2") -> Path:
    """Generate C for ``fn`` and compile it to ``out_dir/<name>.so``; returns the library.
    With ``jacobian``, the library also holds ``jac_<name>``, which ``ca.external`` then uses
    for first derivatives. ``optimisation``: the compiler's -O flag."""
    cc = compiler()
    if cc is None:
        raise CompileError(no_compiler_reason())
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    library = out_dir / f"{fn.name()}.so"
    with tempfile.TemporaryDirectory(prefix="wheelterrain_cg_") as tmp:
        source = _generate(fn, Path(tmp), jacobian)
        _compile(cc, optimisation, source, library, "-lm")
        library.with_suffix(".sha256").write_text(_digest(source) + "\n")
    return library


def _compile(cc: str, optimisation: str, source: Path, library: Path, *libs: str) -> None:
    """Compile the C file ``source`` into the shared library ``library`` (installed whole,
    :func:`install`); CompileError with the compiler's message where it fails."""
    with tempfile.TemporaryDirectory(prefix="wheelterrain_c_") as tmp:
        partial = Path(tmp) / library.name
        run = run_compiler([cc, optimisation, *CFLAGS, str(source), "-o", str(partial), *libs])
        if run.returncode != 0:
            raise CompileError(f"{cc} failed on {source.name}: {run.stderr.strip()[:2000]}")
        install(partial, library)


def cached_library(fn: ca.Function, kind: str, jacobian: bool = False,
                   optimisation: str = "-O2") -> Path:
    """``fn`` compiled once per version into the cache (:func:`cache_directory`/``kind``/, the
    entry named by the SHA-256 of its C): the library's path, compiled now if missing."""
    place = cache_directory() / kind / fingerprint(fn)[:16]
    library = place / f"{fn.name()}.so"
    if not library.is_file():
        with locked(place.parent / f".{place.name}.lock"):  # another process may compile it
            if not library.is_file():
                compile_function(fn, place, jacobian=jacobian, optimisation=optimisation)
    return library


def cached_source(source: Path, optimisation: str = "-O2") -> Path:
    """The C file ``source`` (one of the package's own) compiled once per (its text, the
    compiler) into the cache (:func:`cache_directory`/``source``'s stem/): the library's path,
    compiled now if missing. CompileError where there is no compiler or it fails."""
    cc = compiler()
    if cc is None:
        raise CompileError(no_compiler_reason())
    text = source.read_bytes()
    key = hashlib.sha256(text + b"\0" + cc.encode() + b"\0" + optimisation.encode())
    place = cache_directory() / source.stem / key.hexdigest()[:16]
    library = place / f"{source.stem}.so"
    if library.is_file():
        return library
    make_cache_folder(place)
    with locked(place.parent / f".{place.name}.lock"):  # another process may compile it
        if not library.is_file():
            _compile(cc, optimisation, source, library)
    return library


def make_cache_folder(place: Path) -> None:
    """Create the cache folder ``place`` (and its parents); CompileError saying how to choose
    another where it cannot be."""
    try:
        place.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise CompileError(f"cannot create the cache directory {place} ({err}); set "
                           "WHEELTERRAIN_CACHE to a writable one") from err


def run_compiler(command: list[str]) -> subprocess.CompletedProcess:
    """Run a compiler command line, its output captured; a compiler that cannot be started is
    a CompileError."""
    try:
        return subprocess.run(command, capture_output=True, text=True, check=False)
    except OSError as err:
        raise CompileError(f"cannot run the C compiler {command[0]!r}: {err}") from err


def install(built: Path, library: Path) -> None:
    """Put the library ``built`` (in a temporary folder) at ``library`` atomically: a reader
    never loads half a file, and processes compiling the same library at once do not clash."""
    try:
        with replacing(library) as partial:
            shutil.copyfile(built, partial)
    except OSError as err:
        raise CompileError(f"cannot write {library} ({err})") from err


def _generate(fn: ca.Function, directory: Path, jacobian: bool = False) -> Path:
    source = directory / f"{fn.name()}.c"
    cg = ca.CodeGenerator(source.name, {"with_header": False})
    cg.add(fn)
    if jacobian:
        cg.add(fn.jacobian())
    cg.generate(str(directory) + os.sep)
    return source


def _digest(source: Path) -> str:
    return hashlib.sha256(source.read_bytes()).hexdigest()


@lru_cache(maxsize=64)
def fingerprint(fn: ca.Function) -> str:
    """SHA-256 of the C that CasADi generates for ``fn``: equal iff the compiled library was
    made from this very Function. Remembered per Function object: every pythonfmu instance of
    a process loads the same three libraries (generating their C took 30 ms each, 12 times for
    a rover's four wheels)."""
    with tempfile.TemporaryDirectory(prefix="wheelterrain_fp_") as tmp:
        return _digest(_generate(fn, Path(tmp)))


def vm_arrays(fn: ca.Function):
    """``fn`` on CasADi's virtual machine with :meth:`CompiledFunction.arrays`' convention:
    each output a flat numpy array in CasADi's own (column-major) order, as the compiled
    buffers hold it; the fallback where no library could be compiled."""

    def evaluate(*inputs) -> list[np.ndarray]:
        return [np.asarray(out, dtype=np.float64).ravel(order="F") for out in fn.call(
            list(inputs))]

    return evaluate


class CompiledFunction:
    """Call the compiled C of a CasADi Function with dense inputs of the same shapes.

    ``f(*inputs)`` returns a list of floats, one per (scalar) output; vector outputs are returned
    as lists. Not thread-safe (one set of work buffers per object), like an FMU instance.
    """

    def __init__(self, library: Path, template: ca.Function) -> None:
        name = template.name()
        stamp = Path(library).with_suffix(".sha256")
        if not stamp.is_file() or stamp.read_text().strip() != fingerprint(template):
            raise CompileError(f"{library} was not compiled from this version of {name}")
        self._lib = ctypes.CDLL(str(library))
        self._fn = getattr(self._lib, name)
        self._fn.restype = ctypes.c_int
        work = getattr(self._lib, f"{name}_work")
        sizes = [ctypes.c_longlong() for _ in range(4)]
        if work(*(ctypes.byref(s) for s in sizes)) != 0:
            raise CompileError(f"{library}: {name}_work failed")
        sz_arg, sz_res, sz_iw, sz_w = (s.value for s in sizes)
        self.n_in, self.n_out = template.n_in(), template.n_out()
        self._in = [(ctypes.c_double * template.nnz_in(k))() for k in range(self.n_in)]
        self._out = [(ctypes.c_double * template.nnz_out(k))() for k in range(self.n_out)]
        dbl_p = ctypes.POINTER(ctypes.c_double)
        self._arg = (dbl_p * max(sz_arg, self.n_in))(
            *(ctypes.cast(a, dbl_p) for a in self._in))
        self._res = (dbl_p * max(sz_res, self.n_out))(
            *(ctypes.cast(r, dbl_p) for r in self._out))
        self._iw = (ctypes.c_longlong * max(sz_iw, 1))()
        self._w = (ctypes.c_double * max(sz_w, 1))()
        for k in range(self.n_in):
            if template.nnz_in(k) != template.numel_in(k):
                raise CompileError(f"{name}: input {k} is sparse; dense inputs only")
        self._scalar_out = [template.nnz_out(k) == 1 for k in range(self.n_out)]

    def __call__(self, *inputs) -> list:
        self._evaluate(inputs)
        return [buf[0] if scalar else list(buf)
                for buf, scalar in zip(self._out, self._scalar_out, strict=True)]

    def arrays(self, *inputs) -> list[np.ndarray]:
        """The outputs as numpy arrays (copies): for large outputs, where a list of floats
        costs more than the evaluation (the rover's record of a block of steps)."""
        self._evaluate(inputs)
        return [np.frombuffer(buf, dtype=np.float64).copy() for buf in self._out]

    def _evaluate(self, inputs) -> None:
        for buf, value in zip(self._in, inputs, strict=True):
            if len(buf) == 1:
                buf[0] = value
            else:
                buf[:] = value
        if self._fn(self._arg, self._res, self._iw, self._w, 0) != 0:
            raise CompileError("compiled function reported an error")
