"""Named parameter presets, each a JSON file with its values and provenance.

A preset file holds ``name``, ``description``, ``provenance`` (sources, readings of the paper's
symbols, fitting protocol where fitted) and ``values`` (a partial mapping of table names to numbers;
angles may be written as ``"23deg"``). Missing names take the table default. ``load`` also accepts a
path to such a file, so fitted presets can live outside the package.
"""

from __future__ import annotations

import json
from pathlib import Path

from wheelterrain import package_folder
from wheelterrain.errors import ParameterError
from wheelterrain.parameters import ParameterSet, parse_assignments

DEFAULT_PRESET = "rashid-patch"
"""The one default of every subcommand and face: chosen by held-out and transfer error, not
in-sample error (``wheelterrain validate``; README, first table)."""


def available() -> list[str]:
    """Names of the presets shipped with the package."""
    files = package_folder(__path__).iterdir()
    return sorted(f.name[: -len(".json")] for f in files if f.name.endswith(".json"))


def read(name_or_path: str) -> dict:
    """The raw preset document (name, description, provenance, values)."""
    path = Path(name_or_path)
    if name_or_path.endswith(".json") and path.is_file():
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            raise ParameterError("--preset", name_or_path, f"cannot be read: {err}") from None
    elif name_or_path in available():
        text = (package_folder(__path__) / f"{name_or_path}.json").read_text("utf-8")
    else:
        raise ParameterError(
            "--preset", name_or_path,
            f"is neither a preset ({', '.join(available())}) nor a preset .json file",
        )
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise ParameterError("--preset", name_or_path,
                             f"is not valid JSON ({err.msg} at line {err.lineno}, column "
                             f"{err.colno})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("values"), dict):
        raise ParameterError("--preset", name_or_path, "has no 'values' object")
    return doc


def load(name_or_path: str = DEFAULT_PRESET) -> ParameterSet:
    """A validated :class:`ParameterSet` for a preset name or preset file."""
    doc = read(name_or_path)
    values = parse_assignments(f"{k}={v}" for k, v in doc["values"].items())
    return ParameterSet(values)
