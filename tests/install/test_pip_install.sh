#!/usr/bin/env bash
# ctest pip_install_venv: `pip install .` into a fresh venv (its own site-packages, Debian's numpy
# and pandas through --system-site-packages: no package index is reachable here), then the README's
# Python snippet runs with that venv's interpreter, outside the source and build trees.
#   bash tests/install/test_pip_install.sh SOURCE_DIR WORK_DIR BUDJAM_EXE PYTHON
# WORK_DIR keeps the same layout on every run, so that ccache (CMAKE_CXX_COMPILER_LAUNCHER in the
# environment) finds the objects of the earlier runs.
set -euo pipefail
source=$1 work=$2 exe=$3 python=$4
fail() { echo "test_pip_install: $*" >&2; exit 1; }

# A copy of what `pip install .` needs, as a user's checkout would hold it.
rm -rf "$work"
mkdir -p "$work/src" "$work/user"
for entry in CMakeLists.txt pyproject.toml setup.py setup.cfg README.md cmake include src tools python scripts; do
  cp -r "$source/$entry" "$work/src/"
done

"$python" -m venv --system-site-packages "$work/venv"
venv_python=$work/venv/bin/python
env -u PYTHONPATH "$venv_python" -m pip install --no-build-isolation --no-index -q "$work/src" \
  || fail "pip install --no-build-isolation --no-index . failed"

# The module comes from the venv and reports the command line's version.
read -r where version < <(cd "$work/user" && env -u PYTHONPATH "$venv_python" -c \
  'import budjam; print(budjam.__file__, budjam.__version__)')
[[ $where == "$work/venv/"* ]] || fail "budjam imported from $where, not from the venv"
[[ "budjam $version" == "$("$exe" --version)" ]] || fail "budjam.__version__ $version, budjam --version $("$exe" --version)"

# The README's Python snippet (its first python block), in a directory laid out as the README says.
snippet=$(awk '/^```python$/ { inside = 1; next } inside && /^```$/ { exit } inside' "$source/README.md")
[[ -n $snippet ]] || fail "no python block in README.md"
cd "$work/user"
ln -s "$source/data" data
"$exe" grow data/scenes/demo.toml --out runs/demo --quiet
env -u PYTHONPATH "$venv_python" -c "$snippet" >snippet.out || fail "the README's Python snippet failed in the venv"
echo "test_pip_install: pip install . into a venv, budjam.__version__ and the README snippet work"
