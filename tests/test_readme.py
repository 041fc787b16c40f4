"""The commands of the README and the guides in docs/ as written: every concrete `wheelterrain`
line parses with the options and values it shows, and the `fmpy` lines run (fmpy 0.3.32
renamed `--fmi-type` to `--interface-type`; a README that said the old name failed as
written). And the documentation builds as a site with no warning (links checked)."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import click
import pytest

from wheelterrain import compiled as native
from wheelterrain.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = (README, *sorted((ROOT / "docs").rglob("*.md")))


def readme_commands(tool: str) -> list[list[str]]:
    """The commands of ``tool`` in the bash blocks of the README and docs/, as argument
    lists: comments cut, `a && b` split; lines that show a syntax rather than a command
    (``[--x X]``, ``a|b``, ``...``, the user's own files ``my_*``, a ``tcp://`` scheduler)
    left out."""
    text = "\n".join(page.read_text(encoding="utf-8") for page in PAGES)
    out = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            line = line.split(" #", 1)[0].strip()
            for part in line.split("&&"):
                words = shlex.split(part.strip()) if part.strip() else []
                if not words or words[0] != tool:
                    continue
                if any(s in part for s in ("[", "|", "...", "my_", "tcp://")):
                    continue
                out.append(words[1:])
    return out


def test_every_wheelterrain_command_of_the_readme_parses():
    """Each concrete `wheelterrain ...` line: its sub-command exists, and click accepts every
    option and value (choices, ranges, types) as written. (Parsing only: what runs is tested
    elsewhere, command by command.)"""
    commands = readme_commands("wheelterrain")
    assert len(commands) >= 20, commands  # the README's examples are found, not skipped
    for args in commands:
        command = main.commands.get(args[0])
        assert command is not None, f"wheelterrain {args[0]}: no such command"
        try:
            command.make_context(args[0], list(args[1:]), resilient_parsing=False)
        except click.exceptions.Exit:
            pass  # --help and the like
        except click.UsageError as err:
            pytest.fail(f"wheelterrain {shlex.join(args)}: {err.format_message()}")


@pytest.mark.skipif(native.compiler() is None, reason="needs a C compiler")
def test_the_readme_fmpy_commands_run_as_written(tmp_path, fmu_dir, native_dir):
    """Each `fmpy ...` line runs in a folder laid out as `wheelterrain build --flavor all`
    writes build/ (the FMUs of this test run, conftest.py) and ends with exit status 0."""
    commands = readme_commands("fmpy")
    assert commands
    (tmp_path / "build").mkdir()
    for fmu in fmu_dir.glob("*.fmu"):
        (tmp_path / "build" / fmu.name).symlink_to(fmu)
    (tmp_path / "build" / "native").symlink_to(native_dir, target_is_directory=True)
    for args in commands:
        run = subprocess.run([sys.executable, "-m", "fmpy.cli", *args], cwd=tmp_path,
                             capture_output=True, text=True, timeout=600, check=False)
        assert run.returncode == 0, (shlex.join(["fmpy", *args]), run.stderr[-2000:])


def _build_site(docs_root: Path, out: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                           str(out), "--config-file", str(docs_root / "mkdocs.yml")],
                          cwd=docs_root, capture_output=True, text=True, timeout=600,
                          check=False)


def test_the_documentation_builds_with_no_warning_and_its_links_resolve(tmp_path):
    """`mkdocs build --strict`: warnings are errors, and every link within the site (pages,
    anchors, the generated references, the plots) must resolve. A copy with one broken link
    must fail, so the check is not a check that cannot fail."""
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    run = _build_site(ROOT, tmp_path / "site")
    assert run.returncode == 0, run.stderr[-3000:]
    for page in ("index.html", "reference/parameters.html", "reference/variables.html",
                 "reference/api.html", "report/means_rashid-patch.png"):
        assert (tmp_path / "site" / page).is_file(), page
    parameters = (tmp_path / "site" / "reference" / "parameters.html").read_text()
    assert "rover.gravity" in parameters  # from the one table
    assert "soil.phi" in parameters
    copy = tmp_path / "copy"
    shutil.copytree(ROOT / "docs", copy / "docs")
    for name in ("mkdocs.yml", "README.md"):
        shutil.copy(ROOT / name, copy / name)
    shutil.copytree(ROOT / "validation" / "report", copy / "validation" / "report")
    (copy / "docs" / "cli.md").write_text((ROOT / "docs" / "cli.md").read_text()
                                          + "\n[gone](no-such-page.md)\n")
    broken = _build_site(copy, tmp_path / "broken")
    assert broken.returncode != 0
    assert "no-such-page.md" in broken.stderr


@pytest.mark.skipif(native.compiler() is None, reason="needs a C compiler")
def test_the_python_blocks_run_as_written(tmp_path, fmu_dir, native_dir):
    """Each ```python block of the README and docs/ (the quick start's FMU in fmpy) runs in a
    folder laid out as `wheelterrain build --flavor all` writes build/, exit status 0."""
    blocks = [block for page in PAGES
              for block in re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"),
                                      flags=re.S)]
    assert len(blocks) >= 2  # the README's quick start and the getting-started page
    (tmp_path / "build").mkdir()
    for fmu in fmu_dir.glob("*.fmu"):
        (tmp_path / "build" / fmu.name).symlink_to(fmu)
    (tmp_path / "build" / "native").symlink_to(native_dir, target_is_directory=True)
    for block in blocks:
        run = subprocess.run([sys.executable, "-c", block], cwd=tmp_path, capture_output=True,
                             text=True, timeout=600, check=False)
        assert run.returncode == 0, (block, run.stderr[-2000:])
