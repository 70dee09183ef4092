#!/usr/bin/env bash
# Our BVH against Embree 4 on the same rays (benches/embree.rs): installs
# embreex and numpy from PyPI into target/embree-venv, then runs the bench.
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=target/embree-venv
if ! "$venv/bin/python" -c "import embreex, numpy" 2>/dev/null; then
    echo "== installing embreex into $venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check embreex numpy
fi
LMANIM_EMBREE_PYTHON="$PWD/$venv/bin/python" cargo bench --bench embree
