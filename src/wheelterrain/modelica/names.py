"""The Modelica library's names: the model's snake_case names in MSL's naming convention.

The model, the FMUs and the tables name things once, in snake_case (``drawbar_pull``,
``soil.unloading_stiffness``, ``front_left``). The generated library follows the Modelica
Standard Library's convention instead (Modelica.UsersGuide.Conventions.ModelicaCode.Naming):
lowerCamelCase for variables, components and arguments (``drawbarPull``,
``soil.unloadingStiffness``, ``frontLeft``), an underscore only before a subscript at the
name's end (``x_start``, ``frame_a``, ``k_phi``, ``tau_max``) and in the ``der_`` prefix of a
derivative function's seed arguments (``der_plasticSinkage``, MSL's ``der_u``).

:func:`identifier` is that one rule; :func:`code` applies it to every identifier of a Modelica
text outside its strings, comments and the names of the Modelica Standard Library and
PlanarMechanics (whose own names already follow it). The generator writes its templates and
code with the model's names and passes every class file through :func:`code`, the reference
results' columns through :func:`path`; the tests read results through :func:`path` too. So a
name lives once, in the model, and the library's is derived from it.
"""

from __future__ import annotations

import re

GREEK = frozenset((
    "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
    "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi",
    "omega"))
SUBSCRIPT_WORDS = frozenset(("start", "end", "ref", "max", "min", "nominal", "rel", "deg",
                             "in"))
"""Words kept after an underscore as subscripts (besides single characters, digits and Greek
letters): MSL's ``phi_start``, ``w_ref``, ``tau_max``, ``w_rel``, ``from_deg``."""
FOREIGN_ROOTS = frozenset(("Modelica", "ModelicaServices", "PlanarMechanics", "Complex"))
"""Dotted names rooted here are other libraries' and left as they are."""
FILE_ENDINGS = frozenset(("py", "csv", "txt", "mo", "html", "json", "md"))
FOREIGN_NAMES = frozenset(("f_constant",))
"""Other libraries' names the rule would change, which the library writes undotted (a
modifier of an MSL component: Translational.Sources.ConstantForce's f_constant); kept as
they are. tests/test_modelica_names.py finds every such name from the MSL and PlanarMechanics
sources."""


def _subscript(word: str) -> bool:
    return len(word) == 1 or word.isdigit() or word in GREEK or word in SUBSCRIPT_WORDS


def identifier(name: str) -> str:
    """One identifier of the model in the library: 'drawbar_pull' -> 'drawbarPull',
    'plastic_sinkage_start' -> 'plasticSinkage_start', 'change_start_time' ->
    'changeStartTime' (subscripts only at the end), 'der_slip_angle' -> 'der_slipAngle',
    'k_phi' -> 'k_phi', 'frame_a' -> 'frame_a'. Names without an underscore, names starting
    with a capital (classes), and names with a leading, trailing or doubled underscore (a
    keyword escaped, a tool's own) are left as they are."""
    if "_" not in name or not name[0].islower() or "__" in name or name.endswith("_") \
            or name in FOREIGN_NAMES:
        return name
    words = name.split("_")
    if words[0] == "der":
        return "der_" + identifier("_".join(words[1:]))
    tail = len(words)
    while tail > 1 and _subscript(words[tail - 1]):
        tail -= 1
    head = words[0] + "".join(w[:1].upper() + w[1:] for w in words[1:tail])
    return "_".join((head, *words[tail:]))


def path(name: str) -> str:
    """A variable's path in a model ('front_left.drawbar_pull' -> 'frontLeft.drawbarPull',
    'chassis.sinkage[1]' unchanged): every dotted part through :func:`identifier`."""
    return re.sub(r"[A-Za-z_]\w*", lambda m: identifier(m.group(0)), name)


_TOKEN = re.compile(r'''
    (?P<string>"(?:[^"\\]|\\.)*")
  | (?P<comment>//[^\n]*|/\*.*?\*/)
  | (?P<quoted>'(?:[^'\\]|\\.)*')
  | (?P<number>\d+(?:\.\d*)?(?:[eE][+-]?\d+)?)
  | (?P<name>[A-Za-z_]\w*(?:\s*\.\s*[A-Za-z_]\w*)*)
''', re.VERBOSE | re.DOTALL)


def _name(match: re.Match) -> str:
    text = match.group(0)
    if match.lastgroup != "name":
        return text
    if text.split(".")[0].strip() in FOREIGN_ROOTS:
        return text
    return re.sub(r"[A-Za-z_]\w*", lambda m: identifier(m.group(0)), text)


def code(text: str) -> str:
    """A Modelica text with every identifier of its own through :func:`identifier`: strings,
    comments, quoted identifiers and the dotted names of MSL and PlanarMechanics unchanged."""
    return _TOKEN.sub(_name, text)


def _prose(text: str, known: frozenset[str], tables: frozenset[str]) -> str:
    """One string literal's prose with the library's own names in the convention: a word or
    dotted name is mapped where its parts are identifiers the code pass changes (``known``);
    left alone are table and FMU names (rooted at a table's group, ``tables``: 'soil.k_phi'),
    other libraries' names and file names."""
    def one(match: re.Match) -> str:
        word = match.group(0)
        parts = word.split(".")
        if parts[0] in tables or parts[0] in FOREIGN_ROOTS or parts[-1] in FILE_ENDINGS:
            return word
        return ".".join(identifier(w) if w in known else w for w in word.split("."))
    return re.sub(r"(?<![\w.])[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*", one, text)


def prose(text: str, known: frozenset[str], tables: frozenset[str]) -> str:
    """A Modelica text's strings through :func:`_prose` (its code unchanged)."""
    return _TOKEN.sub(lambda m: _prose(m.group(0), known, tables)
                      if m.lastgroup == "string" else m.group(0), text)


def identifiers(text: str) -> set[str]:
    """The identifiers of a Modelica text's code (outside strings, comments and other libraries'
    dotted names), as written."""
    found = set()
    for match in _TOKEN.finditer(text):
        if match.lastgroup == "name" and match.group(0).split(".")[0].strip() \
                not in FOREIGN_ROOTS:
            found.update(re.findall(r"[A-Za-z_]\w*", match.group(0)))
    return found


def check_distinct(names: set[str]) -> None:
    """Refuse a set of the model's identifiers two of which become one library name (a name
    already in the convention may stand beside the one it is made from)."""
    seen: dict[str, str] = {}
    for name in sorted(n for n in names if identifier(n) != n):
        mapped = identifier(name)
        if seen.get(mapped, name) != name:
            raise ValueError(f"'{seen[mapped]}' and '{name}' would both be '{mapped}' in the "
                             "Modelica library: rename one in the model")
        seen[mapped] = name
