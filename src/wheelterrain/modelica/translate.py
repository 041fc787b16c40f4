"""CasADi SX Functions as Modelica functions, one assignment per SX instruction.

The translation is mechanical: the SX Function's algorithm (its instructions in CasADi's own
evaluation order, on CasADi's own work vector) becomes the algorithm of a Modelica function,
each work slot a protected Real, each instruction one assignment whose right-hand side is the
Modelica expression IEEE 754 evaluates exactly as CasADi's C does (``+ - * /``, ``sqrt``,
``exp``, ``log``, ``sin``, ... are correctly rounded or the same libm calls). So a Modelica tool
evaluates the generated function bit for bit as CasADi does, except where Modelica lacks an
operation and :data:`SUBSTITUTED` writes it in others (``expm1``, ``asinh``): there the
difference is bounded (tests/test_modelica.py).

Every CasADi operation a translated Function uses must be in :data:`OPERATIONS`; an operation
that is not (a new one in the model) is refused with its name, never guessed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca

# CasADi operation -> the Modelica right-hand side, from the operands' names ``a`` and ``b``
OPERATIONS: dict[int, str] = {
    ca.OP_ASSIGN: "{a}",
    ca.OP_ADD: "{a} + {b}",
    ca.OP_SUB: "{a} - {b}",
    ca.OP_MUL: "{a} * {b}",
    ca.OP_DIV: "{a} / {b}",
    ca.OP_NEG: "-{a}",
    ca.OP_EXP: "exp({a})",
    ca.OP_LOG: "log({a})",
    ca.OP_POW: "{a} ^ {b}",
    ca.OP_CONSTPOW: "{a} ^ {b}",
    ca.OP_SQRT: "sqrt({a})",
    ca.OP_SQ: "{a} * {a}",
    ca.OP_TWICE: "{a} + {a}",  # 2*x, exact either way
    ca.OP_SIN: "sin({a})",
    ca.OP_COS: "cos({a})",
    ca.OP_TAN: "tan({a})",
    ca.OP_ASIN: "asin({a})",
    ca.OP_ACOS: "acos({a})",
    ca.OP_ATAN: "atan({a})",
    ca.OP_ATAN2: "atan2({a}, {b})",
    ca.OP_SINH: "sinh({a})",
    ca.OP_COSH: "cosh({a})",
    ca.OP_TANH: "tanh({a})",
    ca.OP_LT: "if {a} < {b} then 1.0 else 0.0",
    ca.OP_LE: "if {a} <= {b} then 1.0 else 0.0",
    ca.OP_EQ: "if {a} == {b} then 1.0 else 0.0",
    ca.OP_NE: "if {a} <> {b} then 1.0 else 0.0",
    ca.OP_NOT: "if {a} == 0.0 then 1.0 else 0.0",
    ca.OP_AND: "if {a} <> 0.0 and {b} <> 0.0 then 1.0 else 0.0",
    ca.OP_OR: "if {a} <> 0.0 or {b} <> 0.0 then 1.0 else 0.0",
    ca.OP_FABS: "abs({a})",
    # CasADi's sign keeps 0 (and NaN) as it is; Modelica's sign(0) is 0 too, its NaN unsaid
    ca.OP_SIGN: "if {a} > 0.0 then 1.0 elseif {a} < 0.0 then -1.0 else {a}",
    ca.OP_IF_ELSE_ZERO: "if {a} == 0.0 then 0.0 else {b}",
    # C's fmin/fmax return the other operand where one is NaN; for numbers they are min/max
    ca.OP_FMIN: "if {a} < {b} or {b} <> {b} then {a} else {b}",
    ca.OP_FMAX: "if {a} > {b} or {b} <> {b} then {a} else {b}",
    ca.OP_INV: "1.0 / {a}",
}

SUBSTITUTED: dict[int, str] = {
    # expm1: the Taylor series where exp(x) - 1 cancels (|x| < 1e-5: the series' next term is
    # below 1e-21 relative), exp(x) - 1 elsewhere (relative error ~1e-16/|x| <= 1e-11)
    ca.OP_EXPM1: "if abs({a}) < 1e-5 then {a} + {a} * {a} * (0.5 + {a} / 6.0) "
                 "else exp({a}) - 1.0",
    # asinh: log(x + sqrt(x^2 + 1)) on |x|, the sign restored; for |x| < 1e-4 the series
    ca.OP_ASINH: "if abs({a}) < 1e-4 then {a} * (1.0 - {a} * {a} / 6.0) else sign({a}) * "
                 "log(abs({a}) + sqrt({a} * {a} + 1.0))",
}
"""Operations Modelica has no function for, written in those it has; their difference from
CasADi's is bounded in tests/test_modelica.py (1e-10 relative)."""

OPERATION_NAMES = {getattr(ca, n): n[3:].lower() for n in dir(ca) if n.startswith("OP_")}


class UnmappedOperationError(ValueError):
    """A CasADi operation the translator has no Modelica form for."""


SI_TYPES = {"m": "Length", "m/s": "Velocity", "m/s2": "Acceleration", "rad": "Angle",
            "rad/s": "AngularVelocity", "rad/s2": "AngularAcceleration", "Pa": "Pressure",
            "1": "DimensionlessRatio"}
"""Unit -> the Modelica.Units.SI type of that unit (a unit with none: Real(unit=...))."""
RATES = {"m": "m/s", "m/s": "m/s2", "rad": "rad/s", "rad/s": "rad/s2", "1": "1/s",
         "Pa": "Pa/s", "rad/m": "rad/(m.s)"}
"""Unit -> the unit of its rate (a derivative function's seed)."""


@dataclass(frozen=True)
class Port:
    """A Modelica input or output of the generated function: ``name``, its length (1: a
    scalar), its Modelica type and description, and its unit (``unit``: its
    Modelica.Units.SI type, or Real with that unit where SI has none; '' for a vector of
    mixed units)."""

    name: str
    size: int = 1
    type: str = "Real"
    description: str = ""
    unit: str = ""

    def declaration(self, direction: str) -> str:
        dims = f"[{self.size}]" if self.size > 1 else ""
        doc = f' "{self.description} [{self.unit}]"' if self.unit else (
            f' "{self.description}"' if self.description else "")
        kind, unit = self.type, ""
        if self.unit and self.type == "Real":
            if self.unit in SI_TYPES:
                kind = f"Modelica.Units.SI.{SI_TYPES[self.unit]}"
            else:
                unit = f'({"each " if self.size > 1 else ""}unit="{self.unit}")'
        return f"  {direction} {kind} {self.name}{dims}{unit}{doc};"

    def rate(self) -> Port:
        """The port of this one's rate, der_<name> (a derivative function's seed or output)."""
        return Port("der_" + self.name, self.size, description=f"d({self.name})/dt",
                    unit=RATES[self.unit] if self.unit else "")

    def element(self, k: int) -> str:
        return f"{self.name}[{k + 1}]" if self.size > 1 else self.name


def literal(value: float) -> str:
    """``value`` as a Modelica Real literal that reads back to the same double."""
    if not math.isfinite(value):
        raise UnmappedOperationError(f"the constant {value!r} has no Modelica literal")
    text = repr(float(value))
    return text if ("e" in text or "." in text) else text + ".0"


def operations(f: ca.Function) -> set[int]:
    """The CasADi operations of ``f``'s algorithm (beyond input, output and constant)."""
    skip = {ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST, ca.OP_PARAMETER}
    return {f.instruction_id(k) for k in range(f.n_instructions())} - skip


def check(f: ca.Function) -> None:
    """Refuse ``f`` if it uses an operation :data:`OPERATIONS` and :data:`SUBSTITUTED` lack."""
    if not f.is_a("SXFunction"):
        raise UnmappedOperationError(f"{f.name()} is a {f.class_name()}, not an SX Function: "
                                "expand it or translate its SX parts")
    missing = sorted(OPERATION_NAMES.get(op, str(op)) for op in operations(f)
                     if op not in OPERATIONS and op not in SUBSTITUTED)
    if missing:
        raise UnmappedOperationError(f"{f.name()} uses CasADi operations with no Modelica form: "
                                + ", ".join(missing))


_WORK = re.compile(r"\bw\d+\b")

CHUNK = 500
"""Instructions per generated function: a Modelica compiler's time can grow with the square of
a function's length (rumoca 0.10: 34 s for 8 000 statements in one function, 9 s in four), so a
longer SX algorithm is cut into pieces of this many instructions, run in order by the function
that carries the name (:func:`functions`)."""


def _w(k: int) -> str:
    return f"w{k}"


def _statement(f: ca.Function, k: int, inputs: Sequence[Port], store) -> str:
    """Instruction ``k`` of ``f`` as one Modelica assignment; ``store(i, j)`` names the place
    of element j of output i."""
    op = f.instruction_id(k)
    out = f.instruction_output(k)
    arg = f.instruction_input(k)
    if op == ca.OP_INPUT:
        return f"  {_w(out[0])} := {inputs[arg[0]].element(arg[1])};"
    if op == ca.OP_OUTPUT:
        return f"  {store(out[0], out[1])} := {_w(arg[0])};"
    if op == ca.OP_CONST:
        return f"  {_w(out[0])} := {literal(f.instruction_constant(k))};"
    form = OPERATIONS.get(op) or SUBSTITUTED[op]
    a = _w(arg[0]) if len(arg) > 0 else ""
    b = _w(arg[1]) if len(arg) > 1 else ""
    return f"  {_w(out[0])} := {form.format(a=a, b=b)};"


def _check_ports(f: ca.Function, inputs: Sequence[Port], outputs: Sequence[Port]) -> None:
    check(f)
    if len(inputs) != f.n_in() or len(outputs) != f.n_out():
        raise ValueError(f"{f.name()} has {f.n_in()} inputs and {f.n_out()} outputs")
    for k, port in enumerate(inputs):
        if f.nnz_in(k) != port.size:
            raise ValueError(f"{f.name()} input {k} has {f.nnz_in(k)} elements, not "
                             f"{port.size}")
    for k, port in enumerate(outputs):
        if f.nnz_out(k) != port.size or f.size1_out(k) * f.size2_out(k) != port.size:
            raise ValueError(f"{f.name()} output {k} is not dense with {port.size} elements")


def _reads_writes(f: ca.Function, k: int) -> tuple[list[int], list[int]]:
    """The work slots instruction ``k`` reads and writes."""
    op = f.instruction_id(k)
    if op == ca.OP_INPUT or op == ca.OP_CONST:
        return [], [f.instruction_output(k)[0]]
    if op == ca.OP_OUTPUT:
        return [f.instruction_input(k)[0]], []
    return list(f.instruction_input(k)), [f.instruction_output(k)[0]]


def _header(name: str, description: str, inputs, outputs) -> list[str]:
    lines = [f'function {name} "{description}"']
    lines += [p.declaration("input") for p in inputs]
    lines += [p.declaration("output") for p in outputs]
    return lines


def _locals(statements: list[str], extra: Sequence[int] = ()) -> list[str]:
    used = sorted({int(tok[1:]) for line in statements for tok in _WORK.findall(line)}
                  | set(extra))
    if not used:
        return []
    return ["protected", *wrap("  Real " + ", ".join(_w(k) for k in used) + ";")]


def _annotation(extra: str) -> str:
    return f"  annotation({', '.join(['Inline=false', *([extra] if extra else [])])});"


def functions(f: ca.Function, name: str, inputs: Sequence[Port], outputs: Sequence[Port],
              description: str, annotation: str = "", pieces: str | None = None,
              chunk: int = CHUNK) -> tuple[str, list[str]]:
    """``f`` as the pure Modelica function ``name`` (``annotation``: more of its annotation,
    e.g. its derivative): ``(text, parts)``.

    Up to ``chunk`` instructions, ``text`` is the whole algorithm and ``parts`` is empty.
    Longer, ``parts`` are functions ``pieces``.part1, part2, ... (``pieces``: the package they
    are to be found in), each running the next ``chunk`` instructions on the work vector they
    are given and returning it (the work slots, then the outputs' elements), and ``text``
    calls them in order: the same instructions in the same order."""
    _check_ports(f, inputs, outputs)
    n = f.n_instructions()
    if n <= chunk:
        def store(i, j):
            return outputs[i].element(j)
        body = [_statement(f, k, inputs, store) for k in range(n)]
        text = [*_header(name, description, inputs, outputs), *_locals(body), "algorithm",
                *body, _annotation(annotation), f"end {name};"]
        return "\n".join(text) + "\n", []
    if pieces is None:
        raise ValueError(f"{f.name()} has {n} instructions: name the package of its parts")
    width = f.sz_w()
    offsets = [0]
    for port in outputs:
        offsets.append(offsets[-1] + port.size)
    size = width + offsets[-1]

    def carried(i, j):
        return f"c[{width + offsets[i] + j + 1}]"

    carry = Port("c_in", size, description="the work vector so far")
    parts, calls = [], []
    arguments = ", ".join(p.name for p in inputs)
    for number, begin in enumerate(range(0, n, chunk), start=1):
        end = min(begin + chunk, n)
        read_first, written = [], set()
        for k in range(begin, end):
            reads, writes = _reads_writes(f, k)
            read_first += [r for r in reads if r not in written and r not in read_first]
            written.update(writes)
        body = [_statement(f, k, inputs, carried) for k in range(begin, end)]
        part = f"part{number}"
        lines = [*_header(part, f"{description}: instructions {begin + 1} to {end}",
                          [*inputs, carry], [Port("c", size, description="the work vector")]),
                 *_locals(body, read_first), "algorithm", "  c := c_in;"]
        lines += [f"  {_w(r)} := c_in[{r + 1}];" for r in read_first]
        lines += body
        lines += [f"  c[{k + 1}] := {_w(k)};" for k in sorted(written)]
        lines += [_annotation(""), f"end {part};"]
        parts.append("\n".join(lines) + "\n")
        start = f"fill(0.0, {size})" if number == 1 else "c"
        calls.append(f"  c := {pieces}.{part}({arguments}, {start});")
    text = [*_header(name, description, inputs, outputs), "protected",
            f'  Real c[{size}] "the work vector: {width} slots, then the outputs";',
            "algorithm", *calls]
    for i, port in enumerate(outputs):
        first = width + offsets[i] + 1
        if port.size == 1:
            text.append(f"  {port.name} := c[{first}];")
        else:
            text.append(f"  {port.name} := c[{first}:{first + port.size - 1}];")
    text += [_annotation(annotation), f"end {name};"]
    return "\n".join(text) + "\n", parts


def external(name: str, inputs: Sequence[Port], outputs: Sequence[Port], description: str,
             clause: str, annotation: str = "") -> str:
    """The Modelica function ``name`` whose body is the external clause ``clause``, declared
    ``pure`` (what an external function is by default; a tool that assumes otherwise, rumoca
    0.10, then accepts its derivative annotation)."""
    header = _header(name, description, inputs, outputs)
    lines = ["pure " + header[0], *header[1:], clause, _annotation(annotation), f"end {name};"]
    return "\n".join(lines) + "\n"


def wrap(text: str, width: int = 100) -> list[str]:
    """A long declaration broken after commas, continued with four spaces."""
    out, line = [], ""
    for piece in text.split(", "):
        candidate = f"{line}, {piece}" if line else piece
        if len(candidate) > width and line:
            out.append(line + ",")
            line = "    " + piece
        else:
            line = candidate
    out.append(line)
    return out
