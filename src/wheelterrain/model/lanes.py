"""Many contact evaluations at once: the model's SX kernels generated as lane-parallel C.

A sweep, a map or a calibration evaluates the contact at thousands of points. CasADi's C is
scalar: one point at a time, one libm call per sine, cosine, exp and pow. Here the same SX
Functions (:func:`wheelterrain.model.contact.lane_kernels`) are written out instruction by
instruction as C over LANES points at once: each instruction becomes a loop over the lanes,
which the compiler turns into vector instructions, and on glibc every sine, cosine, exp and pow
into one call of its vector variant (libmvec, ``#pragma omp declare simd``). Nothing of the
model is written here: the C is the SX Functions' own instruction list, translated one to one,
so it is the expression ``contact.build().contact`` evaluates, with the same case switch
(:func:`~wheelterrain.model.contact._forms`): each point is queued by its case and a full queue
of LANES points runs that case's kernel.

Results equal ``build().contact`` to rounding: libmvec's functions are within 4 ulp and the
compiler may fuse a*b + c; tests bound the difference at 1e-12 relative over random inputs.
The derivatives stay CasADi's (``build().contact_jacobian``).

The library is compiled on first use with the machine's C compiler for the machine it runs on
(-march=native) and kept in the cache directory (:func:`wheelterrain.fmu.compiled.cache_directory`),
named by the SHA-256 of its source, flags and processor; without libmvec (not glibc) the same C is
compiled without the vector math declarations, and without a C compiler :func:`contact` falls
back to CasADi's mapped virtual machine (same numbers to rounding, ~10x slower).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import subprocess
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from wheelterrain.fmu.compiled import CompileError, cache_directory, compiler
from wheelterrain.model import contact as _contact

LANES = 8  # points per kernel call; 8 measured faster than 4 and 16 (two AVX2 vectors)

_BINARY = {
    ca.OP_ADD: "{a}+{b}", ca.OP_SUB: "{a}-{b}", ca.OP_MUL: "{a}*{b}", ca.OP_DIV: "{a}/{b}",
    ca.OP_POW: "pow({a},{b})", ca.OP_CONSTPOW: "pow({a},{b})", ca.OP_ATAN2: "atan2({a},{b})",
    ca.OP_LT: "(double)({a}<{b})", ca.OP_LE: "(double)({a}<={b})",
    ca.OP_EQ: "(double)({a}=={b})", ca.OP_NE: "(double)({a}!={b})",
    # no short-circuit operators: they become branches the compiler cannot vectorise
    ca.OP_AND: "(double)(({a}!=0)&({b}!=0))", ca.OP_OR: "(double)(({a}!=0)|({b}!=0))",
    ca.OP_IF_ELSE_ZERO: "({a}!=0)?{b}:0.0",
    # C's fmin/fmax: a NaN argument yields the other one
    ca.OP_FMIN: "(({b}!={b})|({a}<{b}))?{a}:{b}", ca.OP_FMAX: "(({b}!={b})|({a}>{b}))?{a}:{b}",
    ca.OP_COPYSIGN: "copysign({a},{b})", ca.OP_FMOD: "fmod({a},{b})",
    ca.OP_HYPOT: "hypot({a},{b})",
}
_UNARY = {
    ca.OP_ASSIGN: "{a}", ca.OP_NEG: "-{a}", ca.OP_SQ: "{a}*{a}", ca.OP_TWICE: "2.0*{a}",
    ca.OP_INV: "1.0/{a}", ca.OP_NOT: "(double)({a}==0)", ca.OP_FABS: "fabs({a})",
    ca.OP_SIGN: "({a}<0)?-1.0:(({a}>0)?1.0:{a})",  # CasADi's sign: 0 and NaN pass through
    **{op: f"{name}({{a}})" for op, name in (
        (ca.OP_SQRT, "sqrt"), (ca.OP_EXP, "exp"), (ca.OP_LOG, "log"), (ca.OP_SIN, "sin"),
        (ca.OP_COS, "cos"), (ca.OP_TAN, "tan"), (ca.OP_ASIN, "asin"), (ca.OP_ACOS, "acos"),
        (ca.OP_ATAN, "atan"), (ca.OP_SINH, "sinh"), (ca.OP_COSH, "cosh"), (ca.OP_TANH, "tanh"),
        (ca.OP_ASINH, "asinh"), (ca.OP_ACOSH, "acosh"), (ca.OP_ATANH, "atanh"),
        (ca.OP_ERF, "erf"), (ca.OP_LOG1P, "log1p"), (ca.OP_EXPM1, "expm1"),
        (ca.OP_FLOOR, "floor"), (ca.OP_CEIL, "ceil"))},
}
_MATH = {"sqrt": 1, "exp": 1, "log": 1, "sin": 1, "cos": 1, "tan": 1, "asin": 1, "acos": 1,
         "atan": 1, "sinh": 1, "cosh": 1, "tanh": 1, "asinh": 1, "acosh": 1, "atanh": 1,
         "erf": 1, "log1p": 1, "expm1": 1, "floor": 1, "ceil": 1, "fabs": 1, "pow": 2,
         "atan2": 2, "copysign": 2, "fmod": 2, "hypot": 2}

_KERNEL_ARGS = ("const long* ix, int m, const double* const* in, const long* js, "
                "const long* is, double* const* out, const long* ox, long os")


def kernel_c(fn: ca.Function, name: str) -> str:
    """C for the SX Function ``fn`` over LANES points: ``name(ix, m, in, js, is, out, ox, os)``.

    Lane l reads point ``ix[l]``: element j of input k at ``in[k][j*js[k] + ix[l]*is[k]]`` (an
    input shared by all points has js = 1, is = 0); it writes element j of output k to
    ``out[k][j*os + ox[l]]``, for the first ``m`` lanes only."""
    if not fn.is_a("SXFunction"):
        raise TypeError(f"{fn.name()} is not an SX Function")
    lines = []
    for k in range(fn.n_instructions()):
        op, arg, res = fn.instruction_id(k), fn.instruction_input(k), fn.instruction_output(k)
        if op == ca.OP_OUTPUT:
            lines.append(f"for (l = 0; l < m; ++l) out[{res[0]}][{res[1]}*os + ox[l]] "
                         f"= w{arg[0]}[l];")
            continue
        if op == ca.OP_INPUT:
            rhs = f"in[{arg[0]}][{arg[1]}*js[{arg[0]}] + ix[l]*is[{arg[0]}]]"
        elif op == ca.OP_CONST:
            rhs = repr(float(fn.instruction_constant(k)))
            rhs = {"inf": "(1.0/0.0)", "-inf": "(-1.0/0.0)", "nan": "(0.0/0.0)"}.get(rhs, rhs)
        elif op in _BINARY:
            rhs = _BINARY[op].format(a=f"w{arg[0]}[l]", b=f"w{arg[1]}[l]")
        elif op in _UNARY:
            rhs = _UNARY[op].format(a=f"w{arg[0]}[l]")
        else:
            raise NotImplementedError(f"{fn.name()}: CasADi operation {op} has no C form here")
        lines.append(f"WT_SIMD for (l = 0; l < WT_LANES; ++l) w{res[0]}[l] = {rhs};")
    work = ", ".join(f"w{k}[WT_LANES]" for k in range(fn.sz_w()))
    body = "\n  ".join(lines)
    return (f"static void {name}({_KERNEL_ARGS}) {{\n  int l;\n  double {work};\n  {body}\n}}\n")


_PRELUDE = """\
/* Generated by wheelterrain.model.lanes from the model's CasADi SX Functions: do not edit. */
#define WT_LANES {lanes}
#ifdef WT_SIMD_MATH
#define WT_SIMD _Pragma("omp simd")
#define WT_MATH _Pragma("omp declare simd notinbranch")
#else
#define WT_SIMD
#define WT_MATH
#endif
#ifdef WT_SIMD_MATH2
#define WT_MATH2 _Pragma("omp declare simd notinbranch")
#else
#define WT_MATH2
#endif
{declarations}
typedef void (*wt_kernel)({args});

/* Queue each point by its case; a full queue of WT_LANES points runs that case's kernel. */
static void wt_run(long n, int n_in, const double* const* in, const long* shared,
                   double* const* out, wt_kernel case_kernel, const wt_kernel* forms,
                   int n_forms) {{
  long js[16], is[16], queue[8][WT_LANES], ix[WT_LANES], lane[WT_LANES];
  int count[8] = {{0}}, l, k;
  double cases[WT_LANES];
  double* case_out[1] = {{cases}};
  for (k = 0; k < n_in; ++k) {{ js[k] = shared[k] ? 1 : n; is[k] = shared[k] ? 0 : 1; }}
  for (l = 0; l < WT_LANES; ++l) lane[l] = l;
  for (long i0 = 0; i0 < n; i0 += WT_LANES) {{
    int m = n - i0 < WT_LANES ? (int)(n - i0) : WT_LANES;
    for (l = 0; l < WT_LANES; ++l) ix[l] = i0 + (l < m ? l : m - 1);
    case_kernel(ix, m, in, js, is, case_out, lane, 0);
    for (l = 0; l < m; ++l) {{
      /* CasADi's conditional: a case out of range takes the default, the last form */
      k = cases[l] == 0 ? 0 : (cases[l] == 1 && n_forms > 2 ? 1 : n_forms - 1);
      queue[k][count[k]++] = ix[l];
      if (count[k] == WT_LANES) {{
        forms[k](queue[k], WT_LANES, in, js, is, out, queue[k], n);
        count[k] = 0;
      }}
    }}
  }}
  for (k = 0; k < n_forms; ++k) {{
    if (count[k] == 0) continue;
    for (l = count[k]; l < WT_LANES; ++l) queue[k][l] = queue[k][count[k] - 1];
    forms[k](queue[k], count[k], in, js, is, out, queue[k], n);
  }}
}}
"""


# the vector variants glibc's libmvec has had since 2.22, and those it gained in 2.35
_VECTOR_MATH = {"sin", "cos", "exp", "log", "pow"}
_VECTOR_MATH2 = {"tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "asinh", "acosh",
                 "atanh", "erf", "log1p", "expm1", "hypot"}


def _declarations(source: str) -> str:
    lines = []
    for name in (name for name in _MATH if f"{name}(" in source):
        params = ", ".join(["double"] * _MATH[name])
        tier = "WT_MATH " if name in _VECTOR_MATH else "WT_MATH2 " if name in _VECTOR_MATH2 else ""
        lines.append(f"{tier}extern double {name}({params}) __attribute__((const));")
    return "\n".join(lines)


def contact_source(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> str:
    """The C of ``wt_contact(n, in, shared, out)``: the contact at n points."""
    case, forms = _contact.lane_kernels(nodes)
    kernels = [kernel_c(case, "k_case")] + [kernel_c(f, f"k_{f.name()}") for f in forms]
    names = ", ".join(f"k_{f.name()}" for f in forms)
    entry = f"""
int wt_contact(long n, const double* const* in, const long* shared, double* const* out) {{
  static const wt_kernel forms[{len(forms)}] = {{{names}}};
  wt_run(n, {case.n_in()}, in, shared, out, k_case, forms, {len(forms)});
  return 0;
}}
"""
    body = "\n".join(kernels) + entry
    return _PRELUDE.format(lanes=LANES, declarations=_declarations(body),
                           args=_KERNEL_ARGS) + body


# glibc's vector math (libmvec) first, then its pre-2.35 subset; else the same C, scalar calls.
# --no-undefined: a vector variant this glibc lacks fails the link, not the later load.
_SIMD = ("-fopenmp-simd", "-Wl,--no-undefined", "-lmvec")
_FLAG_SETS = (("-DWT_SIMD_MATH", "-DWT_SIMD_MATH2", *_SIMD), ("-DWT_SIMD_MATH", *_SIMD), ())
_COMMON = ("-O2", "-march=native", "-fno-math-errno", "-fno-trapping-math", "-fPIC", "-shared")


def _processor() -> str:
    try:
        with open("/proc/cpuinfo") as info:
            flags = next((line for line in info if line.startswith("flags")), "")
    except OSError:
        flags = ""
    return f"{platform.machine()} {platform.processor()} {flags}"


def compile_source(source: str, name: str) -> tuple[Path, bool]:
    """Compile ``source`` into the cache once per (source, compiler, processor); returns the
    library and whether it uses glibc's vector math."""
    cc = compiler()
    if cc is None:
        raise CompileError("no C compiler (cc/gcc, or $CC) on PATH")
    key = hashlib.sha256("\0".join((source, cc, " ".join(_COMMON), _processor())).encode())
    place = cache_directory() / "lanes" / key.hexdigest()[:16]
    for flags in _FLAG_SETS:
        library = place / f"{name}_{len(flags)}.so"
        if library.is_file():
            return library, bool(flags)
    place.mkdir(parents=True, exist_ok=True)
    errors = []
    with tempfile.TemporaryDirectory(prefix="wheelterrain_lanes_") as tmp:
        c_file = Path(tmp) / f"{name}.c"
        c_file.write_text(source)
        for flags in _FLAG_SETS:
            library = place / f"{name}_{len(flags)}.so"
            partial = Path(tmp) / library.name
            link = [f for f in flags if f.startswith(("-l", "-Wl"))]
            options = [f for f in flags if f not in link]
            try:
                run = subprocess.run([cc, *_COMMON, *options, str(c_file), "-o", str(partial),
                                      *link, "-lm"], capture_output=True, text=True,
                                     check=False)
            except OSError as err:
                raise CompileError(f"cannot run the C compiler {cc!r}: {err}") from err
            if run.returncode == 0:
                part = library.with_suffix(f".{os.getpid()}.part")
                part.write_bytes(partial.read_bytes())
                os.replace(part, library)
                return library, bool(flags)
            errors.append(run.stderr.strip()[-1000:])
    raise CompileError(f"{cc} failed on the lane kernels: {errors[-1]}")


@dataclass(frozen=True)
class LaneContact:
    """The compiled contact over many points. Call with arrays (or scalars, broadcast)."""

    library: Path
    vector_math: bool
    n_params: int

    @property
    def _entry(self):
        return _load(str(self.library))

    def __call__(self, sinkage, sinkage_rate, slip, wheel_angle, p) -> np.ndarray:
        """CONTACT_OUTPUTS (rows) at each point (columns). ``p``: one parameter vector
        (len(NAMES)) shared by every point, or one per point (len(NAMES) x n)."""
        columns = [np.asarray(x, dtype=float) for x in (sinkage, sinkage_rate, slip,
                                                           wheel_angle)]
        n = max((c.size for c in columns), default=1)
        p = np.asarray(p, dtype=float)
        if p.ndim == 2:
            n = max(n, p.shape[1])
        inputs, shared = [], []
        for column in columns:
            if column.size not in (1, n) or column.ndim > 1:
                raise ValueError(f"inputs must be scalars or 1-D arrays of one length {n}")
            inputs.append(np.ascontiguousarray(column.reshape(-1)))
            shared.append(column.size == 1)
        if p.shape[0] != self.n_params or (p.ndim == 2 and p.shape[1] != n) or p.ndim > 2:
            raise ValueError(f"p must have {self.n_params} rows (one column, or one per point)")
        inputs.append(np.ascontiguousarray(p))
        shared.append(p.ndim == 1)
        out = np.empty((len(_contact.CONTACT_OUTPUTS), n))
        dbl_p = ctypes.POINTER(ctypes.c_double)
        in_ptrs = (dbl_p * len(inputs))(*(a.ctypes.data_as(dbl_p) for a in inputs))
        shared_arr = (ctypes.c_long * len(shared))(*shared)
        out_ptrs = (dbl_p * 1)(out.ctypes.data_as(dbl_p))
        if self._entry(n, in_ptrs, shared_arr, out_ptrs) != 0:
            raise CompileError(f"{self.library.name}: wt_contact failed")
        return out


@lru_cache(maxsize=8)
def _load(library: str):
    entry = ctypes.CDLL(library).wt_contact
    entry.restype = ctypes.c_int
    dbl_pp = ctypes.POINTER(ctypes.POINTER(ctypes.c_double))
    entry.argtypes = [ctypes.c_long, dbl_pp, ctypes.POINTER(ctypes.c_long), dbl_pp]
    return entry


@lru_cache(maxsize=4)
def compiled_contact(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> LaneContact:
    """The lane-parallel contact, compiled on first use (about a minute) and cached."""
    library, vector_math = compile_source(contact_source(nodes), "contact_lanes")
    return LaneContact(library, vector_math, len(_contact.NAMES))
