"""Every figure README.md and docs/ quote is the one its command makes: the quotes against
validation/figures.json (validation/figures.py), and the quick sources made anew."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

from wheelterrain import compiled as native

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def figures():
    spec = importlib.util.spec_from_file_location("figures", ROOT / "validation" / "figures.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["figures"] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_every_quoted_figure_is_the_one_its_command_made(figures):
    """A quote that is not figures.json's (a figure changed by the model and the prose not
    reread), a quote of a figure nothing makes, a table not the one made: each fails here."""
    assert figures.problems(figures.load()) == []


def test_the_check_sees_a_stale_quote(figures, tmp_path, monkeypatch):
    """Not a check that cannot fail: a page quoting an old figure, an unknown key, a changed
    table."""
    store = figures.load()
    key = next(iter(store["figures"]))
    page = tmp_path / "README.md"
    page.write_text(f"<!--f:{key}-->not it<!--/f--> and <!--f:no.such-->1<!--/f-->\n"
                    "<!--table:nested-->\n| stale |\n<!--/table-->\n", encoding="utf-8")
    monkeypatch.setattr(figures, "ROOT", tmp_path)
    monkeypatch.setattr(figures, "QUOTED_IN", ("README.md",))
    found = figures.problems(store)
    assert any(f"{key} quoted 'not it'" in p for p in found)
    assert any("no.such" in p for p in found)
    assert any("the table nested is not the one made" in p for p in found)


def test_every_figure_has_been_made_and_every_source_has_a_command(figures):
    store = figures.load()
    assert set(store["figures"]) == set(figures.FIGURES)
    assert set(store["tables"]) == set(figures.TABLES)
    for name in {f.source for f in figures.FIGURES.values()}:
        assert store["sources"][name]["command"] == figures.SOURCES[name].command()


@pytest.mark.skipif(native.compiler() is None, reason="the quick sources run the native FMUs")
def test_the_quick_sources_still_make_the_quoted_figures(figures, fmu_dir, native_dir, tmp_path,
                                                         monkeypatch):
    """The sources that take seconds (C1-C4 through the native pair) are run again here: the
    model's figures the README quotes are what it makes today, to the digit quoted."""
    (tmp_path / "build").mkdir()
    for fmu in fmu_dir.glob("*.fmu"):
        (tmp_path / "build" / fmu.name).symlink_to(fmu)
    (tmp_path / "build" / "native").symlink_to(native_dir, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(figures, "ROOT", tmp_path)  # the sources run in this folder
    quick = {name: source.run() for name, source in figures.SOURCES.items() if source.quick}
    assert quick
    made = figures.evaluate(quick, {"sources": {}, "figures": {}, "tables": {}}, set(quick))
    stored = figures.load()
    for key, figure in made["figures"].items():
        assert figure["text"] == stored["figures"][key]["text"], key
