"""MkDocs hooks: the reference pages generated from the project's one tables, and the report's
plots, at every build (nothing generated is committed, so nothing can drift).

- reference/parameters.md: every row of :data:`wheelterrain.parameters.ROWS`, grouped by the
  FMU that carries it;
- reference/variables.md: every variable of each FMU (:data:`wheelterrain.fmu.variables.
  VARIABLES`), in value-reference order;
- index.md: the repository's README, its links to docs/ and validation/report/ made the
  site's;
- report/*.png: validation/report's plots, which the guides show.
"""

from __future__ import annotations

from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]


def _cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _number(x: float | None) -> str:
    return "" if x is None else f"{x:g}"


def parameters_page() -> str:
    from wheelterrain.parameters import ROWS

    lines = ["# Parameter reference", "",
             "Generated from the one parameter table (`wheelterrain.parameters`) at every "
             "build of these pages; `wheelterrain params --json` prints the same rows. The "
             "names are the FMU parameter names and the keys of every `--set NAME=VALUE`. "
             "Values in SI units (angles in rad).", ""]
    fmu = None
    for p in ROWS:
        if p.fmu != fmu:
            fmu = p.fmu
            lines += ["", f"## {fmu}.fmu", "",
                      "| name | unit | default | min | max | description | source |",
                      "|---|---|---|---|---|---|---|"]
        lines.append(f"| `{p.name}` | {_cell(p.unit)} | {_number(p.default)} | "
                     f"{_number(p.min)} | {_number(p.max)} | {_cell(p.description)} | "
                     f"{_cell(p.source)} |")
    return "\n".join(lines) + "\n"


def variables_page() -> str:
    from wheelterrain.fmu.variables import VARIABLES, derivative_variables

    lines = ["# FMU variable reference", "",
             "Generated from the one table of FMU variables (`wheelterrain.fmu.variables`) at "
             "every build of these pages. Both flavours carry these variables with these value "
             "references (the native flavour's model exchange interface adds the `der(...)` "
             "variables after them). FMI 3 adds `time` after them.", ""]
    for model, make in VARIABLES.items():
        rows = [*make(), *derivative_variables(model)]
        lines += ["", f"## {model}.fmu", "",
                  "| vr | name | causality | type | unit | start | min | max | description |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for vr, v in enumerate(rows):
            start = "" if v.start is None else (f"{v.start:g}" if isinstance(v.start, float)
                                                else str(v.start))
            lines.append(f"| {vr} | `{v.name}` | {v.causality} | {v.type} | {_cell(v.unit)} | "
                         f"{start} | {_number(v.min)} | {_number(v.max)} | "
                         f"{_cell(v.description)} |")
    return "\n".join(lines) + "\n"


def index_page() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return text.replace("](docs/", "](").replace("](validation/report/", "](report/")


def on_files(files, config):
    for uri, make in (("index.md", index_page), ("reference/parameters.md", parameters_page),
                      ("reference/variables.md", variables_page)):
        files.append(File.generated(config, uri, content=make()))
    for png in sorted((ROOT / "validation" / "report").glob("*.png")):
        files.append(File.generated(config, f"report/{png.name}",
                                    abs_src_path=str(png)))
    return files


def on_page_markdown(markdown, page, config, files):
    """A guide links the report's plots as ../validation/report/NAME.png (right on GitHub);
    in the site they are report/NAME.png."""
    return markdown.replace("](../validation/report/", "](report/")
