"""Files written whole or not at all: every result, plot, FMU, SSP and compiled library the
project writes goes through here, so that no reader ever meets half a file and an interrupted
run (Ctrl-C, SIGTERM, a full disk) leaves nothing behind.

- :func:`replacing`: a temporary path beside the target, renamed onto it when the block ends
  without an exception (``os.replace``: atomic on one file system), removed otherwise; the file
  gets the mode a plain ``open`` would give (the user's umask), not a temporary file's 0600;
- :func:`write_atomic`: text or bytes through :func:`replacing`; a path that is not a regular
  file (/dev/null, /dev/stdout, a named pipe) is written in place;
- :func:`one_set`: a set of files that appear in a folder together, or not at all;
- :func:`locked`: one process at a time in a block (the compiled-library caches: processes
  that need the same library wait for the one compiling it instead of compiling it again).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path


def file_mode() -> int:
    """The mode a new file gets from the user's umask (what open() gives): for a result
    written through a temporary file, which is created 0600."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


@contextlib.contextmanager
def replacing(path: Path) -> Iterator[Path]:
    """A temporary path in ``path``'s folder (created if missing) to write ``path`` through:
    renamed onto ``path`` when the block ends without an exception, removed otherwise. A
    symbolic link is followed (the file it points to is replaced, the link stays)."""
    path = Path(path)
    if path.is_symlink():
        path = path.resolve()
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    os.close(fd)
    partial = Path(name)
    try:
        yield partial
        os.chmod(partial, file_mode())
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)


def write_atomic(path: Path, data: str | bytes) -> None:
    """Write ``data`` (text as UTF-8, or bytes) to ``path`` through :func:`replacing`: never a
    half-written file. A path that is neither missing nor a regular file (/dev/null,
    /dev/stdout, a named pipe) is written in place, never replaced by a regular file."""
    path = Path(path)
    if path.exists() and not path.is_file() and not path.is_dir():
        with path.open("wb" if isinstance(data, bytes) else "w") as f:
            f.write(data)
        return
    with replacing(path) as partial:
        if isinstance(data, bytes):
            partial.write_bytes(data)
        else:
            partial.write_text(data, encoding="utf-8")


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on the file ``path`` (created if missing) for the block: other
    processes asking for it wait. Where the system has no ``fcntl`` (Windows) the block runs
    unlocked (a second process then does the work again; the results are still written whole)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover (not on Linux)
        yield
        return
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


@contextlib.contextmanager
def one_set(out_dir: Path) -> Iterator[Path]:
    """A folder to write a set of result files into; they appear in ``out_dir`` together when
    the block ends without an exception. An interrupted run (Ctrl-C, SIGTERM, an error) leaves
    ``out_dir`` as it was: never part of a set (C1.csv alone), no temporary folder."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(dir=out_dir, prefix=".partial-"))
    try:
        yield staging
        for f in sorted(staging.iterdir()):
            os.replace(f, out_dir / f.name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
