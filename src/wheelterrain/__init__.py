"""wheelterrain: an open wheel-terrain model for grousered rover wheels on loose soil."""

__version__ = "0.1.0"


def package_folder(package_path: list[str]):
    """A package's folder (a :class:`pathlib.Path`): the first entry of its ``__path__`` that
    exists. Inside a pythonfmu FMU the package may have been imported from another instance's
    unzip folder, since deleted by its host; each new instance puts its own bundled copy first
    (:func:`wheelterrain.fmu.slaves.follow_resources`), so data is read from a folder that is
    there."""
    from pathlib import Path

    for entry in package_path:
        if Path(entry).is_dir():
            return Path(entry)
    return Path(package_path[0])
