"""Rig data the package ships (read through :func:`path`), each file stating its source.

- ``paper_table3.json``: the source paper's Table III means (experiment and the authors'
  simulation), C1-C4.
- ``ding2011_single_wheel.csv``: digitised, approximate single-wheel data of Ding et al. 2011
  (J. Terramechanics 48:27-45), smooth and lugged wheel at 80 N, with that soil's parameters in
  the header: a transfer check, never a fit target.

- ``wheel_tests.csv``: the cross-wheel data set, six data sets of four wheels on four soils
  with each soil's own values, in the format of ``wheelterrain validate --data``
  (:mod:`wheelterrain.fit.datasets`; validation/DATA.md documents every data set).

validation/ links to the first two files, so the scripts there and the installed package read
the same bytes.
"""

from __future__ import annotations

from pathlib import Path

from wheelterrain import package_folder


def path(name: str) -> Path:
    """The shipped data file ``name`` (works from an installed wheel, a checkout, and the copy
    bundled in a pythonfmu FMU's resources)."""
    return package_folder(__path__) / name
