"""Many contact evaluations at once: the model's SX kernels generated as lane-parallel C.

A sweep, a map or a calibration evaluates the contact at thousands of points. CasADi's C is
scalar: one point at a time, one libm call per sine, cosine, exp and pow. Here the same SX
Functions (:func:`wheelterrain.model.contact.lane_kernels`) are written out instruction by
instruction as C over LANES points at once: each instruction becomes a loop over the lanes,
which the compiler turns into vector instructions, and on glibc every sine, cosine, exp and pow
into one call of its vector variant (libmvec, ``#pragma omp declare simd``). Nothing of the
model is written here: the C is the SX Functions' own instruction list, translated one to one,
so it is the expression ``model_functions.build().contact`` evaluates, with the same case switch
(:func:`~wheelterrain.model.contact.form_switch`): each point is queued by its case and a full queue
of LANES points runs that case's kernel.

Results equal ``build().contact`` to rounding: libmvec's functions are within 4 ulp and the
compiler may fuse a*b + c; tests bound the difference at 1e-12 relative over random inputs.
The derivatives stay CasADi's (``build().contact_jacobian``).

The library is compiled on first use with the machine's C compiler for the machine it runs on
(-march=native) and kept in the cache directory (:func:`wheelterrain.compiled.cache_directory`),
named by the SHA-256 of its source, flags and processor; without libmvec (not glibc) the same C is
compiled without the vector math declarations, and without a C compiler :func:`contact` falls
back to CasADi's mapped virtual machine (same numbers to rounding, ~10x slower).
"""

from __future__ import annotations

import ctypes
import hashlib
import platform
import sys
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from wheelterrain.compiled import (
    CompileError,
    cache_directory,
    compiler,
    install,
    make_cache_folder,
    no_compiler_reason,
    run_compiler,
)
from wheelterrain.files import locked
from wheelterrain.model import contact as _contact
from wheelterrain.model import solve as _solve

LANES = 8  # points per kernel call; 8 measured faster than 4 and 16 (two AVX2 vectors)
MAX_FORMS = 8  # the most forms a switch of lane kernels dispatches among (wt_cases' queues)

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
#include <stddef.h>
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

/* The points idx[0..m) (0..m-1 when idx is NULL) in blocks of WT_LANES, for kernels of one case. */
static void wt_each(long m, const long* idx, wt_kernel kernel, const double* const* in,
                    const long* js, const long* is, double* const* out, long os) {{
  long ix[WT_LANES];
  int l;
  for (long i0 = 0; i0 < m; i0 += WT_LANES) {{
    int k = m - i0 < WT_LANES ? (int)(m - i0) : WT_LANES;
    for (l = 0; l < WT_LANES; ++l) {{
      long at = i0 + (l < k ? l : k - 1);
      ix[l] = idx ? idx[at] : at;
    }}
    kernel(ix, k, in, js, is, out, ix, os);
  }}
}}

/* The same points, each by the kernel of its case: a point is queued by its case and a full
   queue of WT_LANES points runs that case's kernel. */
static void wt_cases(long m, const long* idx, const double* const* in, const long* js,
                     const long* is, double* const* out, long os, wt_kernel case_kernel,
                     const wt_kernel* forms, int n_forms) {{
  long queue[{max_forms}][WT_LANES], ix[WT_LANES], lane[WT_LANES];
  int count[{max_forms}] = {{0}}, l, k;
  double cases[WT_LANES];
  double* case_out[1] = {{cases}};
  for (l = 0; l < WT_LANES; ++l) lane[l] = l;
  for (long i0 = 0; i0 < m; i0 += WT_LANES) {{
    int c = m - i0 < WT_LANES ? (int)(m - i0) : WT_LANES;
    for (l = 0; l < WT_LANES; ++l) {{
      long at = i0 + (l < c ? l : c - 1);
      ix[l] = idx ? idx[at] : at;
    }}
    case_kernel(ix, c, in, js, is, case_out, lane, 0);
    for (l = 0; l < c; ++l) {{
      /* CasADi's conditional: case k < n_forms - 1 takes form k; any other value (out of
         range, not an integer) the default, the last form */
      k = n_forms - 1;
      for (int f = 0; f < n_forms - 1; ++f) if (cases[l] == f) k = f;
      queue[k][count[k]++] = ix[l];
      if (count[k] == WT_LANES) {{
        forms[k](queue[k], WT_LANES, in, js, is, out, queue[k], os);
        count[k] = 0;
      }}
    }}
  }}
  for (k = 0; k < n_forms; ++k) {{
    if (count[k] == 0) continue;
    for (l = count[k]; l < WT_LANES; ++l) queue[k][l] = queue[k][count[k] - 1];
    forms[k](queue[k], count[k], in, js, is, out, queue[k], os);
  }}
}}

/* Strides of inputs given per point (element j of point i at j*n + i) or shared (at j). */
static void wt_strides(long n, int n_in, const long* shared, long* js, long* is) {{
  for (int k = 0; k < n_in; ++k) {{ js[k] = shared[k] ? 1 : n; is[k] = shared[k] ? 0 : 1; }}
}}
"""


def solve_source(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> str:
    """The C of ``wt_solve(n, in, shared, out)``: the steady state at n points (inputs load,
    slip, guess, first, last, p; outputs STEADY_OUTPUTS, as ``build().steady``), in chunks of
    WT_CHUNK points: the pruned scan (:func:`~wheelterrain.model.solve.scan_values`), the
    bracket, the refined second iterate, at most NEWTON_ITERATIONS Newton iterations for the
    points not yet converged, the final angle, the ripple-free contact there and the outputs:
    the order in which ``build().steady`` evaluates the same pieces. A point with a sinkage guess
    (finite, > 0) starts warm instead (:func:`~wheelterrain.model.solve.solve_start_warm`):
    the scan's two ends and Newton from the guess; ``first`` and ``last``, where finite, are
    those two ends' Fz_static (from ``wt_scan_ends``: a sweep computes them once per slip)."""
    k = _solve.solve_lane_kernels(nodes)
    singles = ("case", "scan_plan", "scan_low", "start", "start_warm", "refine",
               "newton_angle", "newton_update", "solve_angle", "finish")
    kernels = [kernel_c(k[name], f"k_{name}") for name in singles]
    kernels += [kernel_c(f, f"k_{f.name()}") for f in (*k["fz"], *k["fz_d"], *k["static"])]
    scan = _solve.scan_angles()
    n_scan = len(scan)
    fz = ", ".join(f"k_{f.name()}" for f in k["fz"])
    fz_d = ", ".join(f"k_{f.name()}" for f in k["fz_d"])
    static = ", ".join(f"k_{f.name()}" for f in k["static"])
    rows = {name: row for row, name in enumerate(_solve.STEADY_OUTPUTS)}
    f_row = rows["normal_force_static"]
    angles = ", ".join(repr(float(a)) for a in scan)
    size, done = _solve.STATE_SIZE, _solve.STATE_DONE
    entry = f"""
#define WT_CHUNK 256
/* The points idx[0..m) take their next Newton state (rows of WT_CHUNK, {size} of them). */
static void wt_take(long m, const long* idx, const double* next, double* state) {{
  for (long a = 0; a < m; ++a)
    for (int j = 0; j < {size}; ++j)
      state[j * WT_CHUNK + idx[a]] = next[j * WT_CHUNK + idx[a]];
}}

int wt_solve(long n, const double* const* in, const long* shared, double* const* out) {{
  static const wt_kernel fz[3] = {{{fz}}}, fz_d[3] = {{{fz_d}}}, contact[3] = {{{static}}};
  static const double scan[{n_scan}] = {{{angles}}};
  double values[{n_scan} * WT_CHUNK], state[{size} * WT_CHUNK], next[{size} * WT_CHUNK];
  double fd[2 * WT_CHUNK], theta[WT_CHUNK], capacity[WT_CHUNK], w_safe[WT_CHUNK];
  double plan[{n_scan - 2} * WT_CHUNK], low[3 * WT_CHUNK];
  long active[WT_CHUNK], cold[WT_CHUNK], warm[WT_CHUNK], need[WT_CHUNK], some[WT_CHUNK];
  long first_end[WT_CHUNK];
  long js[6], is[6];
  wt_strides(n, 6, shared, js, is);
  for (long c0 = 0; c0 < n; c0 += WT_CHUNK) {{
    long m = n - c0 < WT_CHUNK ? n - c0 : WT_CHUNK, i, n_cold = 0, n_warm = 0, n_need = 0;
    long n_first = 0;
    const double* load = in[0] + c0 * is[0];
    const double* slip = in[1] + c0 * is[1];
    const double* guess = in[2] + c0 * is[2];
    const double* first = in[3] + c0 * is[3];
    const double* last = in[4] + c0 * is[4];
    const double* p = in[5] + c0 * is[5];
    /* a finite, positive sinkage guess starts a point warm; NaN (or <= 0) cold. A warm point
       needs the scan's two ends, unless given (finite): they depend on slip and p only */
    for (i = 0; i < m; ++i) {{
      double g = guess[i * is[2]], a = first[i * is[3]], b = last[i * is[4]];
      int warm_point = g > 0 && g - g == 0, given = a - a == 0 && b - b == 0;
      if (warm_point) warm[n_warm++] = i; else cold[n_cold++] = i;
      if (!warm_point || !given) need[n_need++] = i;
      if (warm_point && !given) first_end[n_first++] = i;
      if (warm_point && given) {{
        values[i] = a;
        values[({n_scan} - 1) * WT_CHUNK + i] = b;
      }}
    }}
    /* at an entry angle per point: theta, slip, p */
    const double* at[3] = {{theta, slip, p}};
    long at_js[3] = {{1, js[1], js[5]}}, at_is[3] = {{1, is[1], is[5]}};
    for (i = 0; i < m; ++i) theta[i] = scan[{n_scan} - 1];
    {{  /* fully buried (the capacity): every point that has not been given it */
      double* o[1] = {{values + ({n_scan} - 1) * WT_CHUNK}};
      wt_cases(n_need, need, at, at_js, at_is, o, 0, k_case, fz, 3);
    }}
    {{  /* a warm point lacking the scan's first end */
      double* o[1] = {{values}};
      for (i = 0; i < m; ++i) theta[i] = scan[0];
      wt_cases(n_first, first_end, at, at_js, at_is, o, 0, k_case, fz, 3);
    }}
    {{  /* a cold point: the inner angles its scan plan keeps, then its bracket's low end
         (solve.scan_values); the rest stay NaN, angles below the load */
      const double* a[3] = {{load, slip, p}};
      long a_js[3] = {{js[0], js[1], js[5]}}, a_is[3] = {{is[0], is[1], is[5]}};
      double* o[1] = {{plan}};
      wt_each(n_cold, cold, k_scan_plan, a, a_js, a_is, o, WT_CHUNK);
    }}
    for (i = 0; i < n_cold; ++i) values[cold[i]] = 0.0 / 0.0;
    for (int s = 1; s < {n_scan} - 1; ++s) {{
      long n_some = 0;
      double* o[1] = {{values + s * WT_CHUNK}};
      for (i = 0; i < n_cold; ++i) {{
        if (plan[(s - 1) * WT_CHUNK + cold[i]] != 0) some[n_some++] = cold[i];
        else values[s * WT_CHUNK + cold[i]] = 0.0 / 0.0;
      }}
      for (i = 0; i < m; ++i) theta[i] = scan[s];
      wt_cases(n_some, some, at, at_js, at_is, o, 0, k_case, fz, 3);
    }}
    {{
      const double* a[3] = {{load, values, plan}};
      long a_js[3] = {{js[0], WT_CHUNK, WT_CHUNK}}, a_is[3] = {{is[0], 1, 1}};
      double* o[3] = {{low, low + WT_CHUNK, low + 2 * WT_CHUNK}};
      long n_some = 0;
      wt_each(n_cold, cold, k_scan_low, a, a_js, a_is, o, 0);
      for (i = 0; i < n_cold; ++i) {{
        theta[cold[i]] = low[WT_CHUNK + cold[i]];
        if (low[2 * WT_CHUNK + cold[i]] != 0) some[n_some++] = cold[i];
      }}
      double* f_low[1] = {{fd}};
      wt_cases(n_some, some, at, at_js, at_is, f_low, 0, k_case, fz, 3);
      for (i = 0; i < n_some; ++i)
        values[(long)low[some[i]] * WT_CHUNK + some[i]] = fd[some[i]];
    }}
    {{
      const double* a[2] = {{load, values}};
      long a_js[2] = {{js[0], WT_CHUNK}}, a_is[2] = {{is[0], 1}};
      double* o[3] = {{state, capacity, w_safe}};
      wt_each(n_cold, cold, k_start, a, a_js, a_is, o, WT_CHUNK);
    }}
    {{
      const double* a[5] = {{load, values, values + ({n_scan} - 1) * WT_CHUNK, guess, p}};
      long a_js[5] = {{js[0], 1, 1, js[2], js[5]}}, a_is[5] = {{is[0], 1, 1, is[2], is[5]}};
      double* o[3] = {{state, capacity, w_safe}};
      wt_each(n_warm, warm, k_start_warm, a, a_js, a_is, o, WT_CHUNK);
    }}
    {{  /* a cold point's second iterate, from Fz_static at its first (solve.refine) */
      const double* s_in[1] = {{state}};
      long s_js[1] = {{WT_CHUNK}}, s_is[1] = {{1}};
      double* s_out[1] = {{theta}};
      wt_each(n_cold, cold, k_newton_angle, s_in, s_js, s_is, s_out, 0);
      double* f_out[1] = {{fd}};
      wt_cases(n_cold, cold, at, at_js, at_is, f_out, 0, k_case, fz, 3);
      const double* r_in[3] = {{state, fd, w_safe}};
      long r_js[3] = {{WT_CHUNK, 1, 1}}, r_is[3] = {{1, 1, 1}};
      double* r_out[1] = {{next}};
      wt_each(n_cold, cold, k_refine, r_in, r_js, r_is, r_out, WT_CHUNK);
      wt_take(n_cold, cold, next, state);
    }}
    for (int iteration = 0; iteration < {_solve.NEWTON_ITERATIONS}; ++iteration) {{
      long n_active = 0;
      for (i = 0; i < m; ++i)
        if (state[{done} * WT_CHUNK + i] == 0) active[n_active++] = i;
      if (n_active == 0) break;
      const double* s_in[1] = {{state}};
      long s_js[1] = {{WT_CHUNK}}, s_is[1] = {{1}};
      double* s_out[1] = {{theta}};
      wt_each(n_active, active, k_newton_angle, s_in, s_js, s_is, s_out, 0);
      double* d_out[2] = {{fd, fd + WT_CHUNK}};
      wt_cases(n_active, active, at, at_js, at_is, d_out, 0, k_case, fz_d, 3);
      const double* u_in[4] = {{state, fd, fd + WT_CHUNK, w_safe}};
      long u_js[4] = {{WT_CHUNK, 1, 1, 1}}, u_is[4] = {{1, 1, 1, 1}};
      double* u_out[1] = {{next}};
      wt_each(n_active, active, k_newton_update, u_in, u_js, u_is, u_out, WT_CHUNK);
      wt_take(n_active, active, next, state);
    }}
    {{
      const double* a[2] = {{load, state}};
      long a_js[2] = {{js[0], WT_CHUNK}}, a_is[2] = {{is[0], 1}};
      double* o[1] = {{theta}};
      wt_each(m, NULL, k_solve_angle, a, a_js, a_is, o, 0);
    }}
    {{  /* the ripple-free contact at the final angle, into rows 1.. of the outputs */
      double* o[1] = {{out[0] + n + c0}};
      wt_cases(m, NULL, at, at_js, at_is, o, n, k_case, contact, 3);
    }}
    {{
      const double* a[4] = {{load, state, out[0] + {f_row} * n + c0, p}};
      long a_js[4] = {{js[0], WT_CHUNK, 1, js[5]}}, a_is[4] = {{is[0], 1, 1, is[5]}};
      double* o[3] = {{out[0] + c0, out[0] + {rows["residual"]} * n + c0,
                      out[0] + {rows["last_step"]} * n + c0}};
      wt_each(m, NULL, k_finish, a, a_js, a_is, o, 0);
    }}
    for (i = 0; i < m; ++i) out[0][{rows["capacity"]} * n + c0 + i] = capacity[i];
  }}
  return 0;
}}

/* Fz_static at the scan's two ends (slip, p -> 2 rows): a sweep's warm starts share them. */
int wt_scan_ends(long n, const double* const* in, const long* shared, double* const* out) {{
  static const wt_kernel fz[3] = {{{fz}}};
  static const double ends[2] = {{{float(scan[0])!r}, {float(scan[-1])!r}}};
  double theta[WT_CHUNK];
  long js[2], is[2];
  wt_strides(n, 2, shared, js, is);
  for (long c0 = 0; c0 < n; c0 += WT_CHUNK) {{
    long m = n - c0 < WT_CHUNK ? n - c0 : WT_CHUNK;
    const double* at[3] = {{theta, in[0] + c0 * is[0], in[1] + c0 * is[1]}};
    long at_js[3] = {{1, js[0], js[1]}}, at_is[3] = {{1, is[0], is[1]}};
    for (int e = 0; e < 2; ++e) {{
      double* o[1] = {{out[0] + e * n + c0}};
      for (long i = 0; i < m; ++i) theta[i] = ends[e];
      wt_cases(m, NULL, at, at_js, at_is, o, 0, k_case, fz, 3);
    }}
  }}
  return 0;
}}
"""
    body = "\n".join(kernels) + entry
    return _PRELUDE.format(lanes=LANES, max_forms=MAX_FORMS, declarations=_declarations(body),
                           args=_KERNEL_ARGS) + body


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


def _cases_source(entry: str, case: ca.Function, forms: tuple, prefix: str = "") -> str:
    """The C of ``entry(n, in, shared, out)``: the SX Functions ``forms`` at n points, each
    point by the form its ``case`` picks (:func:`kernel_c`'s kernels, ``prefix`` on the case
    kernel's name)."""
    if len(forms) > MAX_FORMS:  # wt_cases' queues
        raise ValueError(f"{entry}: {len(forms)} forms, at most {MAX_FORMS}")
    case_name = f"k_{prefix}case"
    kernels = [kernel_c(case, case_name)] + [kernel_c(f, f"k_{f.name()}") for f in forms]
    names = ", ".join(f"k_{f.name()}" for f in forms)
    body = "\n".join(kernels) + f"""
int {entry}(long n, const double* const* in, const long* shared, double* const* out) {{
  static const wt_kernel forms[{len(forms)}] = {{{names}}};
  long js[{case.n_in()}], is[{case.n_in()}];
  wt_strides(n, {case.n_in()}, shared, js, is);
  wt_cases(n, NULL, in, js, is, out, n, {case_name}, forms, {len(forms)});
  return 0;
}}
"""
    return _PRELUDE.format(lanes=LANES, max_forms=MAX_FORMS, declarations=_declarations(body),
                           args=_KERNEL_ARGS) + body


def contact_source(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> str:
    """The C of ``wt_contact(n, in, shared, out)``: the contact at n points."""
    return _cases_source("wt_contact", *_contact.lane_kernels(nodes))


def lateral_source(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> str:
    """The C of ``wt_lateral(n, in, shared, out)``: the side force (LATERAL_OUTPUTS) at n points
    of (sinkage, slip, slip_angle, turn_slip, p), each by the kernel of its case
    (:func:`wheelterrain.model.contact.lateral_kernels`), as ``build().lateral``."""
    return _cases_source("wt_lateral", *_contact.lateral_kernels(nodes), prefix="lateral_")


# glibc's vector math (libmvec) first, then its pre-2.35 subset; else the same C, scalar calls.
# --no-undefined: a vector variant this glibc lacks fails the link, not the later load.
_SIMD = ("-fopenmp-simd", "-Wl,--no-undefined", "-lmvec")
_FLAG_SETS = (("-DWT_SIMD_MATH", "-DWT_SIMD_MATH2", *_SIMD), ("-DWT_SIMD_MATH", *_SIMD), ())
_COMMON = ("-O1", "-march=native", "-fno-math-errno", "-fno-trapping-math", "-fPIC", "-shared")


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
        raise CompileError(no_compiler_reason())
    key = hashlib.sha256("\0".join((source, cc, " ".join(_COMMON), _processor())).encode())
    place = cache_directory() / "lanes" / key.hexdigest()[:16]
    found = _cached_lanes(place, name)
    if found is not None:
        return found
    make_cache_folder(place)
    with locked(place / f".{name}.lock"):  # another process may be compiling it
        found = _cached_lanes(place, name)
        return found if found is not None else _compile_lanes(source, name, place, cc)


def _cached_lanes(place: Path, name: str) -> tuple[Path, bool] | None:
    """The library ``name`` in the cache folder ``place`` (the best flag set's), or None."""
    for flags in _FLAG_SETS:
        library = place / f"{name}_{len(flags)}.so"
        if library.is_file():
            return library, bool(flags)
    return None


def _compile_lanes(source: str, name: str, place: Path, cc: str) -> tuple[Path, bool]:
    """Compile ``source`` into ``place`` with the first flag set the compiler takes."""
    # the first use waits for the compiler (20-80 s): say so, once, rather than stall silently
    print(f"wheelterrain: compiling {name} for this processor, once (kept in {place})",
          file=sys.stderr, flush=True)
    errors = []
    with tempfile.TemporaryDirectory(prefix="wheelterrain_lanes_") as tmp:
        c_file = Path(tmp) / f"{name}.c"
        c_file.write_text(source)
        for flags in _FLAG_SETS:
            library = place / f"{name}_{len(flags)}.so"
            partial = Path(tmp) / library.name
            link = [f for f in flags if f.startswith(("-l", "-Wl"))]
            options = [f for f in flags if f not in link]
            run = run_compiler([cc, *_COMMON, *options, str(c_file), "-o", str(partial), *link,
                                "-lm"])
            if run.returncode == 0:
                install(partial, library)
                return library, bool(flags)
            errors.append(run.stderr.strip()[-1000:])
    raise CompileError(f"{cc} failed on the lane kernels: {errors[-1]}")


@dataclass(frozen=True)
class LaneFunction:
    """A compiled lane entry (``wt_contact`` or ``wt_solve``) over many points. Call it with
    the per-point inputs (scalars are shared by every point, arrays give one value per point)
    and ``p``: one parameter vector (len(NAMES)) shared by every point, or one per point
    (len(NAMES) x n). Returns one row per output, one column per point."""

    library: Path
    symbol: str
    outputs: tuple[str, ...]
    vector_math: bool
    n_params: int

    def __call__(self, *args) -> np.ndarray:
        *columns, p = args
        columns = [np.asarray(x, dtype=float) for x in columns]
        p = np.asarray(p, dtype=float)
        n = max([c.size for c in columns] + ([p.shape[1]] if p.ndim == 2 else []))
        inputs, shared = [], []
        for column in columns:
            if column.size not in (1, n) or column.ndim > 1:
                raise ValueError(f"inputs must be scalars or 1-D arrays of one length {n}")
            inputs.append(np.ascontiguousarray(column.reshape(-1)))
            shared.append(column.size == 1)
        if p.ndim not in (1, 2) or p.shape[0] != self.n_params or (p.ndim == 2
                                                                    and p.shape[1] != n):
            raise ValueError(f"p must have {self.n_params} rows (one column, or one per point)")
        inputs.append(np.ascontiguousarray(p))
        shared.append(p.ndim == 1)
        out = np.empty((len(self.outputs), n))
        dbl_p = ctypes.POINTER(ctypes.c_double)
        in_ptrs = (dbl_p * len(inputs))(*(a.ctypes.data_as(dbl_p) for a in inputs))
        shared_arr = (ctypes.c_long * len(shared))(*shared)
        out_ptrs = (dbl_p * 1)(out.ctypes.data_as(dbl_p))
        if _load(str(self.library), self.symbol)(n, in_ptrs, shared_arr, out_ptrs) != 0:
            raise CompileError(f"{self.library.name}: {self.symbol} failed")
        return out


@lru_cache(maxsize=8)
def _load(library: str, symbol: str):
    entry = getattr(ctypes.CDLL(library), symbol)
    entry.restype = ctypes.c_int
    dbl_pp = ctypes.POINTER(ctypes.POINTER(ctypes.c_double))
    entry.argtypes = [ctypes.c_long, dbl_pp, ctypes.POINTER(ctypes.c_long), dbl_pp]
    return entry


@lru_cache(maxsize=4)
def compiled_contact(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> LaneFunction:
    """``contact(sinkage, sinkage_rate, slip, wheel_angle, p)`` -> CONTACT_OUTPUTS, compiled on
    first use (about a minute) and cached."""
    library, vector_math = compile_source(contact_source(nodes), "contact_lanes")
    return LaneFunction(library, "wt_contact", _contact.CONTACT_OUTPUTS, vector_math,
                        len(_contact.NAMES))


@lru_cache(maxsize=4)
def compiled_solve(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> LaneFunction:
    """``solve(load, slip, guess, first, last, p)`` -> STEADY_OUTPUTS, those of
    ``build().steady`` where ``guess`` is NaN, warm-started from the sinkage ``guess`` [m]
    elsewhere (with the scan's end values ``first``, ``last`` where finite: from
    :func:`compiled_scan_ends`); compiled on first use (about 80 s) and cached."""
    library, vector_math = compile_source(solve_source(nodes), "solve_lanes")
    return LaneFunction(library, "wt_solve", _solve.STEADY_OUTPUTS, vector_math,
                        len(_contact.NAMES))


@lru_cache(maxsize=4)
def compiled_scan_ends(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> LaneFunction:
    """``ends(slip, p)`` -> Fz_static at the solve's smallest scan angle and fully buried (the
    capacity), in the library of :func:`compiled_solve`."""
    solve = compiled_solve(nodes)
    return LaneFunction(solve.library, "wt_scan_ends", ("first", "last"), solve.vector_math,
                        solve.n_params)


@lru_cache(maxsize=4)
def compiled_lateral(nodes: tuple[int, int] = _contact.DEFAULT_NODES) -> LaneFunction:
    """``lateral(sinkage, slip, slip_angle, turn_slip, p)`` -> LATERAL_OUTPUTS
    (``build().lateral``'s), compiled on first use and cached."""
    library, vector_math = compile_source(lateral_source(nodes), "lateral_lanes")
    return LaneFunction(library, "wt_lateral", _contact.LATERAL_OUTPUTS, vector_math,
                        len(_contact.NAMES))
