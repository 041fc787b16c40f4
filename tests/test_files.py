"""Files written whole (wheelterrain.files): a lock that makes a second process wait."""

from __future__ import annotations

import subprocess
import sys
import time

from wheelterrain import files

HOLD = """
import sys, time
from pathlib import Path
from wheelterrain import files
with files.locked(Path(sys.argv[1])):
    Path(sys.argv[2]).write_text("held")
    time.sleep(1.0)
    Path(sys.argv[2]).write_text("released")
"""


def test_a_lock_held_by_another_process_is_waited_for(tmp_path):
    """Two processes that need the same compiled library: the second waits for the first
    instead of compiling it again (compiled.cached_library, lanes, Functions.External)."""
    lock, marker = tmp_path / "x.lock", tmp_path / "state"
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(lock), str(marker)])
    try:
        for _ in range(200):  # until the other process holds it
            if marker.exists():
                break
            time.sleep(0.02)
        assert marker.read_text() == "held"
        with files.locked(lock):
            assert marker.read_text() == "released"
    finally:
        holder.wait(timeout=30)
    assert holder.returncode == 0
