#!/usr/bin/env bash
# Build OMSimulator (OpenModelica's FMI/SSP co-simulation engine) from its public sources, for
# the OMSimulator check of the C1-C4 SSP files (tests/test_native_fmus.py, skipped without it).
# It has no binary on PyPI (the PyPI package downloads one from build.openmodelica.org at
# install time) and none in Debian, so CI, which reaches PyPI and Debian only, skips that test.
#
#     bash validation/build_omsimulator.sh [PREFIX]        # default PREFIX: ~/.local/omsimulator
#     OMSIMULATOR=PREFIX/bin/OMSimulator python3 -m pytest tests/test_native_fmus.py -k omsimulator
#
# Needs git, cmake, ninja (Debian: git cmake ninja-build g++) and network access to GitHub;
# about 25 minutes on two cores. The commit is the one the check was measured with
# (OMSimulator v3.0.0.post114-gacb56d9). At it, OMSimulator's CMake files ask for the
# targets oms::3rd::sundials::cvode and ::kinsol, which its pinned 3rdParty commit still calls
# oms::3rd::cvode and ::kinsol: two alias lines bridge the rename.
set -euo pipefail
PREFIX="${1:-$HOME/.local/omsimulator}"
COMMIT=acb56d9d9c8ecbe4408fcee0f2a548daf3d7573b
THIRD_PARTY=1168b8e255c1d57563a5f90ae31df2ba62f3c676
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
git clone --quiet https://github.com/OpenModelica/OMSimulator.git "$WORK/OMSimulator"
cd "$WORK/OMSimulator"
git checkout --quiet "$COMMIT"
git clone --quiet https://github.com/OpenModelica/OMSimulator-3rdParty.git 3rdParty
git -C 3rdParty checkout --quiet "$THIRD_PARTY"
sed -i '/^add_library(oms::3rd::kinsol ALIAS sundials_kinsol_static)/a\
add_library(oms::3rd::sundials::cvode ALIAS sundials_cvode_static)\
add_library(oms::3rd::sundials::kinsol ALIAS sundials_kinsol_static)' 3rdParty/CMakeLists.txt
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$PREFIX" >/dev/null
cmake --build build --target install
"$PREFIX/bin/OMSimulator" --version
echo "OMSimulator installed: OMSIMULATOR=$PREFIX/bin/OMSimulator"
