"""The figures README.md and docs/ quote, made by the commands that make them, and the check
that every quote is still what those commands print.

    python3 validation/figures.py                    # check every quote (exit 1 on a drift)
    python3 validation/figures.py --update           # rerun every source (~15 min), rewrite
                                                     # validation/figures.json and the quotes
    python3 validation/figures.py --update --only reproduce validate   # some sources only
    python3 validation/figures.py --requote          # the quotes anew from the kept documents

A quote in Markdown is ``<!--f:KEY-->TEXT<!--/f-->`` (an inline figure; TEXT is the figure
formatted as FIGURES says) or a block ``<!--table:NAME-->`` ... ``<!--/table-->`` (a table
TABLES writes whole). GitHub and MkDocs show TEXT and the table; the markers are invisible.
``--update`` reruns the sources, keeps what each printed in validation/figures/<source>.json and
the figures read from it in validation/figures.json (with the command and the date of each),
and rewrites every quote from it: what changed is then in the
diff, for the prose around it to be read again. The check needs no run: it compares every quote
with figures.json (tests/test_figures.py runs it, and recomputes the quick sources).
"""

from __future__ import annotations

import argparse
import datetime
import json
import re
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STORE = ROOT / "validation" / "figures.json"
RAW = ROOT / "validation" / "figures"
"""Each source's JSON as its command printed it (RAW/<source>.json): the evidence the figures
are read from, and what a table of two sources reads when only one is run again."""
QUOTED_IN = ("README.md", "docs/*.md", "validation/*.md")
INLINE = re.compile(r"<!--f:([\w.\-]+)-->(.*?)<!--/f-->", re.S)
BLOCK = re.compile(r"(<!--table:([\w.\-]+)-->\n)(.*?)(<!--/table-->)", re.S)


@dataclass(frozen=True)
class Source:
    """A command whose JSON the figures come from: ``argv`` with {json} (the file it writes)
    and {tmp} (a scratch folder) filled in; ``python`` runs a script, else the CLI."""

    argv: tuple[str, ...]
    python: bool = False
    quick: bool = False  # a few seconds: tests/test_figures.py recomputes it

    def command(self) -> str:
        head = "python3" if self.python else "wheelterrain"
        return " ".join([head, *self.argv]).replace(" {json}", "").replace(
            " --out {tmp}", "").replace("--json {json}", "--json")

    def run(self) -> dict:
        with tempfile.TemporaryDirectory(prefix="wheelterrain_figures_") as tmp:
            target = Path(tmp) / "out.json"
            argv = [a.format(json=target, tmp=tmp) for a in self.argv]
            if self.python:
                run = subprocess.run([sys.executable, *argv], cwd=ROOT, capture_output=True,
                                     text=True, check=False)
                if run.returncode != 0:
                    raise RuntimeError(f"{self.command()} failed: {run.stderr[-2000:]}")
                return json.loads(run.stdout)
            run = subprocess.run([sys.executable, "-m", "wheelterrain.cli", *argv], cwd=ROOT,
                                 capture_output=True, text=True, check=False)
            if run.returncode != 0:
                raise RuntimeError(f"{self.command()} failed: {run.stderr[-2000:]}")
            return json.loads(target.read_text())


SOURCES = {
    "reproduce": Source(("reproduce", "--json", "{json}", "--out", "{tmp}"), quick=True),
    "reproduce-me": Source(("reproduce", "--interface", "me", "--json", "{json}", "--out",
                            "{tmp}")),
    "validate": Source(("validate", "--json", "{json}")),
    **{f"rover-{s}-{g}": Source(("rover", "--scenario", s, "--gravity", g, "--json", "{json}",
                                 "--out", "{tmp}"))
       for s in ("level", "slope", "descent") for g in ("earth", "moon")},
    "multipass": Source(("multipass", "--slip", "0.1,0.3,0.5", "--scm-reference", "--json",
                         "{json}", "--out", "{tmp}")),
    "bench-rover": Source(("benchmarks/rover.py", "--quick", "--json"), python=True),
    "bench-fmus": Source(("benchmarks/fmus.py", "--quick", "--json"), python=True),
    "bench-core": Source(("benchmarks/core.py", "--quick", "--json"), python=True),
}


@dataclass(frozen=True)
class Figure:
    source: str
    get: Callable[[dict], float | str | None]
    fmt: str = "{:.2f}"

    def text(self, value) -> str:
        return "none" if value is None else self.fmt.format(value)


def _multipass_runs(doc: dict, who: str) -> list[dict]:
    """The multipass document's runs: the model's, or the SCM reference's."""
    return doc["runs"] if who == "model" else doc["scm_reference"]["runs"]


def _mode_text(mode: dict | None) -> str:
    """The predicted stability mode in words: what grows, how fast, at what frequency."""
    if mode is None:
        return "none"
    kind = ("a divergence" if mode["frequency_hz"] == 0
            else f"a {mode['frequency_hz']:.2g} Hz oscillation")
    return f"{kind} growing at {mode['growth_rate_per_s']:.2g}/s, {mode['leading']} leading"


def _nested(doc: dict, dataset: str, role: str) -> dict:
    """The nested protocol's row of ``dataset`` in ``role``: "rule", "classical" or "line"."""
    return next(r for r in doc["rows"] if r["protocol"] == "nested-leave-one-dataset-out"
                and r["dataset"] == dataset and r["role"] == role)


def _judged(role: str, key: str, scale: float = 1.0) -> Callable[[dict], float | None]:
    """A nested mean of ``role`` (validate's ``judged_by``) times ``scale``."""
    def get(d: dict) -> float | None:
        value = d["default_form_rule"]["judged_by"][role][key]
        return None if value is None else scale * value
    return get


def _paired(name: str, metric: str, key: str) -> Callable[[dict], float | str]:
    return lambda d: d["paired"][name][metric][key]


def _case(doc: dict, case: str) -> dict:
    return next(c for c in doc["cases"] if c["case"] == case)


def _wheel_mean(doc: dict, key: str, wheels: tuple[str, ...]) -> float:
    return sum(w[key] for w in doc["wheels"] if w["name"] in wheels) / len(wheels)


FRONT, REAR = ("front_left", "front_right"), ("rear_left", "rear_right")

FIGURES: dict[str, Figure] = {
    # the rig, C1-C4 through the FMUs (wheelterrain reproduce, default preset)
    "reproduce.pull_mae": Figure("reproduce", lambda d: d["mean_absolute_error"]["drawbar_pull"]),
    "reproduce.normal_force_mae": Figure(
        "reproduce", lambda d: d["mean_absolute_error"]["normal_force"]),
    "reproduce.sinkage_mae_mm": Figure(
        "reproduce", lambda d: 1e3 * d["mean_absolute_error"]["sinkage"]),
    **{f"reproduce.{c}.sinkage_mm": Figure("reproduce",
                                            lambda d, c=c: 1e3 * _case(d, c)["sinkage"])
       for c in ("C1", "C2", "C3", "C4")},
    **{f"reproduce.{c}.pull": Figure("reproduce", lambda d, c=c: _case(d, c)["drawbar_pull"])
       for c in ("C1", "C2", "C3", "C4")},
    # the cross-wheel headline (wheelterrain validate, nested protocol)
    **{f"validate.{role}.pull": Figure("validate", _judged(role, "drawbar_pull_mae"))
       for role in ("rule", "classical", "line")},
    **{f"validate.{role}.pull_per_load": Figure(
        "validate", _judged(role, "drawbar_pull_mae_per_load"), "{:.3f}")
       for role in ("rule", "classical", "line")},
    **{f"validate.{role}.sinkage_mm": Figure("validate", _judged(role, "sinkage_mae", 1e3),
                                             "{:.1f}") for role in ("rule", "classical", "line")},
    **{f"validate.{role}.sinkage_per_radius": Figure(
        "validate", _judged(role, "sinkage_mae_per_radius"), "{:.3f}")
       for role in ("rule", "classical", "line")},
    **{f"validate.{role}.increment_mm": Figure(
        "validate", _judged(role, "sinkage_increment_mae", 1e3), "{:.1f}")
       for role in ("rule", "classical", "line")},
    **{f"validate.{role}.surface_datum_sinkage_mm": Figure(
        "validate", lambda d, role=role: 1e3 * d["default_form_rule"]["judged_by"][role][
            "without_inferred_datum"]["sinkage_mae"], "{:.1f}")
       for role in ("rule", "classical", "line")},
    **{f"validate.{role}.coverage": Figure("validate", _judged(role, "interval_coverage", 100),
                                           "{:.0f} %") for role in ("rule", "classical")},
    **{f"validate.paired.{name}.{short}.{key}": Figure(
        "validate", _paired(name, metric, key), fmt)
       for name in ("rule-classical", "rule-line")
       for short, metric in (("pull", "drawbar_pull_mae_per_load"),
                             ("sinkage", "sinkage_mae_per_radius"),
                             ("increment", "sinkage_increment_mae_per_radius"))
       for key, fmt in (("mean", "{:+.3f}"), ("standard_error", "{:.3f}"),
                        ("better_on", "{}"), ("verdict", "{}"))},
    "validate.oracle.gain": Figure("validate", lambda d: -d["oracle"]["mean"], "{:.3f}"),
    "validate.oracle.standard_error": Figure(
        "validate", lambda d: d["oracle"]["standard_error"], "{:.3f}"),
    # the rover (wheelterrain rover --json, in process)
    **{f"rover.{g}.level.sinkage_{end}_mm": Figure(
        f"rover-level-{g}", lambda d, ws=ws: 1e3 * _wheel_mean(d, "mean_sinkage", ws))
       for g in ("earth", "moon") for end, ws in (("front", FRONT), ("rear", REAR))},
    **{f"rover.{g}.level.rtf": Figure(f"rover-level-{g}", lambda d: d["real_time_factor"],
                                      "{:.0f}") for g in ("earth", "moon")},
    **{f"rover.{g}.slope.stall_deg": Figure(f"rover-slope-{g}", lambda d: d["stall_slope_deg"],
                                            "{:.1f}°") for g in ("earth", "moon")},
    **{f"rover.{g}.slope.predicted_deg": Figure(
        f"rover-slope-{g}", lambda d: d["predicted_stall_slope_deg"], "{:.1f}°")
       for g in ("earth", "moon")},
    **{f"rover.{g}.slope.cause": Figure(f"rover-slope-{g}", lambda d: d["stall_cause"], "{}")
       for g in ("earth", "moon")},
    **{f"rover.{g}.slope.predicted_limit": Figure(
        f"rover-slope-{g}", lambda d: d["predicted_stall_limit"], "{}")
       for g in ("earth", "moon")},
    **{f"rover.{g}.descent.slide_deg": Figure(
        f"rover-descent-{g}", lambda d: f"slides at {abs(d['slide_slope_deg']):.1f}°"
        if d["slide_slope_deg"] is not None else "holds 20°", "{}")
       for g in ("earth", "moon")},
    **{f"rover.{g}.descent.cause": Figure(f"rover-descent-{g}", lambda d: d["stall_cause"]
                                          or "no slide", "{}") for g in ("earth", "moon")},
    # multi-pass on the rig, 62 N (wheelterrain multipass --scm-reference --json)
    **{f"multipass.{who}.{slip}.pass{k}.{what}": Figure(
        "multipass", lambda d, who=who, i=i, k=k, key=key, scale=scale:
        scale * _multipass_runs(d, who)[i]["passes"][k - 1][key], fmt)
       for who in ("model", "scm") for i, slip in enumerate(("0.1", "0.3", "0.5"))
       for k in range(1, 6)
       for what, key, scale, fmt in (("pull", "traction_coefficient", 1.0, "{:.3f}"),
                                     ("increment_mm", "sinkage_increment", 1e3, "{:.2f}"))},
    **{f"rover.{g}.slope.mode": Figure(
        f"rover-slope-{g}", lambda d: _mode_text(d.get("predicted_stability_mode")), "{}")
       for g in ("earth", "moon")},
    **{f"rover.{g}.descent.predicted_deg": Figure(
        f"rover-descent-{g}", lambda d: abs(d["predicted_descent_limit_deg"]), "{:.1f}°")
       for g in ("earth", "moon")},
    **{f"rover.{g}.descent.locked_deg": Figure(
        f"rover-descent-{g}", lambda d: abs(d["locked_limit_deg"])
        if d.get("locked_limit_deg") is not None else None, "{:.1f}°")
       for g in ("earth", "moon")},
    **{f"rover.{g}.descent.predicted_limit": Figure(
        f"rover-descent-{g}", lambda d: d["predicted_descent_limit"], "{}")
       for g in ("earth", "moon")},
    # speed (benchmarks, --quick, median of repeats on the machine that ran them)
    "bench.rover.in_process": Figure("bench-rover", lambda d: d["rover_rtf_fastest"], "{:.0f}×"),
    "bench.rover.fmpy": Figure("bench-rover", lambda d: d["rover_rtf_fmpy"], "{:.1f}×"),
    "bench.fmus.c1_c4_ratio": Figure(
        "bench-fmus", lambda d: d["c1_c4_ratio_pythonfmu_over_fastest"], "{:.1f}×"),
    "bench.fmus.c1_c4_fastest_s": Figure("bench-fmus", lambda d: d["c1_c4_fastest_s"],
                                         "{:.2f} s"),
    "bench.fmus.native_step_us": Figure("bench-fmus", lambda d: 1e6 * d["native_step_c_host_s"],
                                        "{:.2f} µs"),
    "bench.fmus.pythonfmu_start_up_rover_s": Figure(
        "bench-fmus", lambda d: d["pythonfmu_start_up_rover_s"], "{:.2f} s"),
    "bench.core.force_ratio": Figure(
        "bench-core", lambda d: d["force_eval_reference_s"] / d["force_eval_s"], "{:.0f}×"),
    "bench.core.solve_ratio": Figure(
        "bench-core", lambda d: d["solve_reference_s"] / d["solve_s"], "{:.0f}×"),
    "bench.core.lateral_ratio": Figure(
        "bench-core", lambda d: d["lateral_eval_speedup"], "{:.0f}×"),
}


def _percent(x) -> str:
    return "–" if x is None else f"{100 * x:.0f} %"


NAMES = {"rashid-rig": "Rashid rig C1–C4", "ding2011-smooth": "Ding 2011 smooth",
         "ding2011-lugged": "Ding 2011 lugged", "kls1-smooth": "KLS-1 smooth",
         "kls1-lugged": "KLS-1 lugged", "rashid1-fjs1": "Rashid-1 wheel, FJS-1"}


def _pair(row: dict) -> str:
    """A nested row's pull and sinkage, in N and mm and as shares of W and R."""
    return (f"{row['drawbar_pull_mae']:.2f} N ({row['drawbar_pull_mae_per_load']:.3f} W), "
            f"{1e3 * row['sinkage_mae']:.1f} mm ({row['sinkage_mae_per_radius']:.3f} R)")


def _nested_table(docs: dict[str, dict]) -> str:
    """The README's headline: per held-out data set, the form the fold's rule chose beside the
    two baselines under the same protocol (the line, classical Wong-Reece), in N and mm and as
    shares of the load W and the radius R; the sinkage also from the set's lowest slip."""
    doc = docs["validate"]
    lines = ["| held-out data set (points, load) | line (2 free): pull, sinkage | classical "
             "Wong–Reece (0 free): pull, sinkage (90 % coverage) | the fold's rule chose | that "
             "form: pull, sinkage (90 % coverage) | sinkage from the lowest slip: line, "
             "classical, rule |", "|---|---|---|---|---|---|"]
    for dataset, name in NAMES.items():
        line, classical, rule = (_nested(doc, dataset, role)
                                 for role in ("line", "classical", "rule"))
        load = rule["drawbar_pull_mae"] / rule["drawbar_pull_mae_per_load"]
        datum = " †" if rule["sinkage_from"] == "rest" else ""
        lines.append(
            f"| {name}{datum} ({rule['points']}, {load:.3g} N) | {_pair(line)} | "
            f"{_pair(classical)} ({_percent(classical['interval_coverage'])}) | "
            f"`{rule['model']}` | {_pair(rule)} ({_percent(rule['interval_coverage'])}) | "
            + ", ".join(f"{1e3 * r['sinkage_increment_mae']:.1f}"
                        for r in (line, classical, rule)) + " mm |")
    judged = doc["default_form_rule"]["judged_by"]
    a, c, b = judged["line"], judged["classical"], judged["rule"]

    def mean(e: dict) -> str:
        return (f"{e['drawbar_pull_mae']:.2f} N ({e['drawbar_pull_mae_per_load']:.3f} W), "
                f"{1e3 * e['sinkage_mae']:.1f} mm ({e['sinkage_mae_per_radius']:.3f} R)")
    lines.append(f"| mean over data sets | {mean(a)} | {mean(c)} "
                 f"({_percent(c['interval_coverage'])}) | {len(b['forms'])} forms | {mean(b)} "
                 f"({_percent(b['interval_coverage'])}) | "
                 + ", ".join(f"{1e3 * e['sinkage_increment_mae']:.1f}" for e in (a, c, b))
                 + " mm |")
    return "\n".join(lines) + "\n"


RIG_PRESETS = ("line", "rashid-patch", "paper-table2", "rashid-calibrated", "paper-table2-arc")


def _rig_table(docs: dict[str, dict]) -> str:
    """The rig's C1-C4 (quasi-static, `validate`): held-out, in-sample and transfer errors."""
    rows = docs["validate"]["rows"]

    def row(model: str, protocol: str, data: str = "") -> dict | None:
        return next((r for r in rows if r["model"] == model and r["protocol"] == protocol
                     and str(r.get("data", "")).startswith(data)), None)

    def cell(r: dict | None) -> str:
        if r is None:
            return "—"
        mark = " *in-sample*" if r["in_sample"] else ""
        return f"{r['drawbar_pull_mae']:.2f} N, {1e3 * r['sinkage_mae']:.2f} mm{mark}"

    lines = ["| model | free | leave-one-out | the paper's C2-only protocol | C1–C4 as "
             "shipped | transfer to Ding 2011: lugged / smooth |",
             "|---|---|---|---|---|---|"]
    for model in RIG_PRESETS:
        shipped = row(model, "all-case")
        free = len(shipped["free"]) if shipped else "—"
        transfer = [row(model, "transfer", f"ding2011-{w}") for w in ("lugged", "smooth")]
        moved = "—" if transfer[0] is None else f"{cell(transfer[0])} / {cell(transfer[1])}"
        lines.append(f"| `{model}` | {free} | {cell(row(model, 'leave-one-out'))} | "
                     f"{cell(row(model, 'c2-only'))} | {cell(shipped)} | {moved} |")
    return "\n".join(lines) + "\n"


def _interfaces_table(docs: dict[str, dict]) -> str:
    """C1-C4 through co-simulation and model exchange (the native pair; the pythonfmu pair and
    FMI 3 give co-simulation's numbers bit for bit: tests/test_native_fmus.py)."""
    cs, me = docs["reproduce"], docs["reproduce-me"]

    def cells(doc: dict) -> tuple[str, str]:
        cases = [_case(doc, c) for c in ("C1", "C2", "C3", "C4")]
        return (" / ".join(f"{c['drawbar_pull']:.2f}" for c in cases),
                " / ".join(f"{1e3 * c['sinkage']:.2f}" for c in cases))

    worst = max(abs(_case(me, c)[k] - _case(cs, c)[k]) / abs(_case(cs, c)[k])
                for c in ("C1", "C2", "C3", "C4") for k in ("drawbar_pull", "sinkage"))
    rows = ["| interface | command | C1 / C2 / C3 / C4 drawbar pull [N] | sinkage [mm] | "
            "largest relative difference to co-simulation |", "|---|---|---|---|---|"]
    pull, sink = cells(cs)
    rows.append(f"| co-simulation (pythonfmu and native, FMI 2 and 3: the same numbers) | "
                f"`wheelterrain reproduce` | {pull} | {sink} | — |")
    pull, sink = cells(me)
    rows.append(f"| model exchange (native, RK4 master) | `wheelterrain reproduce --interface "
                f"me` | {pull} | {sink} | {worst:.1e} |")
    return "\n".join(rows) + "\n"


TABLES: dict[str, tuple[tuple[str, ...], Callable[[dict], str]]] = {
    "interfaces": (("reproduce", "reproduce-me"), _interfaces_table),
    "nested": (("validate",), _nested_table),
    "rig": (("validate",), _rig_table),
}


# --- the store and the quotes ----------------------------------------------------------------

def load() -> dict:
    return json.loads(STORE.read_text(encoding="utf-8")) if STORE.is_file() else {
        "sources": {}, "figures": {}, "tables": {}}


def raw_documents() -> dict[str, dict]:
    """The sources' JSON kept in RAW, by source."""
    return {p.stem: json.loads(p.read_text(encoding="utf-8"))
            for p in sorted(RAW.glob("*.json")) if p.stem in SOURCES}


def evaluate(docs: dict[str, dict], store: dict, only: set[str] | None = None) -> dict:
    """``store`` with the figures and tables made anew from the sources' documents ``docs``
    (those of ``only`` where given, and every table that reads one of them)."""
    for key, figure in FIGURES.items():
        if figure.source in docs and (only is None or figure.source in only):
            value = figure.get(docs[figure.source])
            store["figures"][key] = {"value": value, "text": figure.text(value),
                                     "source": figure.source}
    for name, (needs, render) in TABLES.items():
        if all(s in docs for s in needs) and (only is None or set(needs) & only):
            store["tables"][name] = render(docs)
    return store


def save(store: dict) -> None:
    from wheelterrain.files import write_atomic

    write_atomic(STORE, json.dumps(store, indent=1, sort_keys=True, ensure_ascii=False) + "\n")


def quoted_files() -> list[Path]:
    return sorted({p for pattern in QUOTED_IN for p in ROOT.glob(pattern)})


def problems(store: dict) -> list[str]:
    """Every quote that is not figures.json's figure or table, and every key nothing makes."""
    out = []
    for path in quoted_files():
        text = path.read_text(encoding="utf-8")
        where = path.relative_to(ROOT)
        for key, quoted in INLINE.findall(text):
            if key not in FIGURES:
                out.append(f"{where}: <!--f:{key}--> names no figure of validation/figures.py")
            elif key not in store["figures"]:
                out.append(f"{where}: {key} has not been made (--update)")
            elif quoted != store["figures"][key]["text"]:
                out.append(f"{where}: {key} quoted {quoted!r}, made "
                           f"{store['figures'][key]['text']!r}")
        for _, name, quoted, _ in BLOCK.findall(text):
            if name not in TABLES:
                out.append(f"{where}: <!--table:{name}--> names no table of "
                           "validation/figures.py")
            elif quoted != store["tables"].get(name):
                out.append(f"{where}: the table {name} is not the one made")
    return out


def rewrite_quotes(store: dict) -> list[Path]:
    """Every quote made anew from ``store``; returns the files that changed."""
    changed = []
    for path in quoted_files():
        text = path.read_text(encoding="utf-8")

        def inline(m: re.Match) -> str:
            made = store["figures"].get(m.group(1))
            return m.group(0) if made is None else f"<!--f:{m.group(1)}-->{made['text']}<!--/f-->"

        def block(m: re.Match) -> str:
            made = store["tables"].get(m.group(2))
            return m.group(0) if made is None else m.group(1) + made + m.group(4)

        new = BLOCK.sub(block, INLINE.sub(inline, text))
        if new != text:
            path.write_text(new, encoding="utf-8")
            changed.append(path)
    return changed


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--update", action="store_true",
                    help="rerun the sources, rewrite validation/figures.json and the quotes")
    ap.add_argument("--only", nargs="*", choices=sorted(SOURCES), metavar="SOURCE",
                    help=f"with --update, only these sources ({', '.join(SOURCES)})")
    ap.add_argument("--requote", action="store_true",
                    help="read the figures anew from the documents kept (a figure's format or "
                    "a table changed), rewrite the quotes; no source runs")
    args = ap.parse_args()
    store = load()
    if args.requote:
        save(evaluate(raw_documents(), store))
        for path in rewrite_quotes(store):
            print(f"rewrote the quotes in {path.relative_to(ROOT)}", file=sys.stderr)
    if args.update:
        from wheelterrain.files import write_atomic

        chosen = args.only or list(SOURCES)
        for name in chosen:  # each source's document and figures kept as soon as it has run
            print(f"{SOURCES[name].command()} ...", file=sys.stderr, flush=True)
            document = SOURCES[name].run()
            write_atomic(RAW / f"{name}.json", json.dumps(document, indent=1) + "\n")
            evaluate(raw_documents(), store, {name})
            store["sources"][name] = {"command": SOURCES[name].command(),
                                      "date": datetime.date.today().isoformat()}
            save(store)
        evaluate(raw_documents(), store)  # every figure from the documents kept
        save(store)
        for path in rewrite_quotes(store):
            print(f"rewrote the quotes in {path.relative_to(ROOT)}", file=sys.stderr)
    found = problems(store)
    for line in found:
        print(line)
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
