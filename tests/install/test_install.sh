#!/usr/bin/env bash
# ctest install_package: `cmake --install` into a scratch prefix, then use what was installed as a
# user would. Fails at the first property that does not hold.
#   bash tests/install/test_install.sh BUILD_DIR SOURCE_DIR PYTHON_DIR PYTHON
set -euo pipefail
build=$1 source=$2 pydir=$3 python=${4:-/usr/bin/python3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
packing=$source/tests/data/saddle_jamming_L15_seed3.pack
fail() { echo "test_install: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$prefix" >/dev/null

# The executable runs from the prefix.
[[ $("$prefix/bin/budjam" --version) == "budjam "* ]] || fail "installed budjam --version"

# The man page documents every subcommand (generated from the help text).
if [[ -f $build/budjam.1 ]]; then
  man=$prefix/share/man/man1/budjam.1
  [[ -s $man ]] || fail "no man page at $man"
  for sub in $("$prefix/bin/budjam" --help | awk '/^Subcommands:/ { s = 1; next } s && /^  [a-z]/ { print $1 }'); do
    grep -q "^\.SS budjam $sub\$" "$man" || fail "man page has no section for '$sub'"
  done
fi

# Bash completion completes subcommands and a subcommand's options.
completion=$prefix/share/bash-completion/completions/budjam
[[ -f $completion ]] || fail "no bash completion at $completion"
complete_words() {  # prints COMPREPLY for the command line "$@" (the last word is completed)
  bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _budjam; printf "%s\n" "${COMPREPLY[@]}"' \
    _ "$completion" "$@"
}
[[ $(complete_words "$prefix/bin/budjam" exp) == export ]] || fail "completion of 'budjam exp'"
[[ $(complete_words "$prefix/bin/budjam" export --fo) == --format ]] || fail "completion of 'budjam export --fo'"
[[ $(complete_words "$prefix/bin/budjam" export --format g) == gsd ]] || fail "completion of 'budjam export --format g'"
# Debian's bash-completion (part of the set-up) finds it by itself: its loader looks in
# share/bash-completion/completions of every XDG data directory.
loader=/usr/share/bash-completion/bash_completion
if [[ -f $loader ]]; then
  XDG_DATA_DIRS=$prefix/share bash -c 'source "$1"; _completion_loader budjam; complete -p budjam' _ "$loader" \
    | grep -q -- "-F _budjam budjam" || fail "bash-completion's loader does not find the installed completion"
fi

# find_package(budjam) from a separate project; its program agrees with `budjam rigidity`.
cmake -S "$source/tests/install/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null || fail "configuring a project with find_package(budjam)"
cmake --build "$work/consumer" >/dev/null || fail "building against the installed libraries"
read -r n phi contacts excess < <("$work/consumer/packing_fraction" "$packing")
expected=$("$prefix/bin/budjam" rigidity "$packing" --json | "$python" -c \
  'import json, sys; j = json.load(sys.stdin); print(j["N"], j["contacts"], 2 * j["contacts_load_bearing"] - (6 * j["N_nr"] - 2 * j["N_u"] - 2))')
[[ "$n $contacts $excess" == "$expected" ]] ||
  fail "consumer says N, contacts, excess contacts = $n $contacts $excess, budjam rigidity $expected"

# The shared library of that project, holding the static libraries, loads and agrees with `budjam moduli`.
shear=$source/tests/data/shear_conventions_differ_L8.pack
plugin=$(find "$work/consumer" -name 'libbudjam_plugin.so' | head -1)
[[ -n $plugin ]] || fail "no shared library built against the installed static libraries"
"$python" - "$plugin" "$shear" "$prefix/bin/budjam" <<'PY' || fail "the shared library's G differs from budjam moduli's"
import ctypes, json, subprocess, sys
lib = ctypes.CDLL(sys.argv[1])
lib.budjam_plugin_shear_modulus.restype = ctypes.c_double
g = lib.budjam_plugin_shear_modulus(sys.argv[2].encode())
cli = json.loads(subprocess.run([sys.argv[3], "moduli", sys.argv[2], "--json"], check=True, capture_output=True,
                                text=True).stdout)
sys.exit(0 if g == cli["G"] else 1)
PY

# The Python module imports from the prefix, outside the source and build trees.
if [[ -d $prefix/$pydir/budjam ]]; then
  where=$(cd "$work" && PYTHONPATH=$prefix/$pydir "$python" -c \
    "import budjam; print(budjam.__file__); print(budjam.read_packing('$packing').N)")
  [[ $(sed -n 1p <<<"$where") == "$prefix/$pydir/budjam/__init__.py" ]] || fail "budjam imported from $(sed -n 1p <<<"$where")"
  [[ $(sed -n 2p <<<"$where") == "$n" ]] || fail "Python reads N = $(sed -n 2p <<<"$where"), expected $n"
fi
echo "test_install: prefix layout, man page, completion, find_package(budjam) and import budjam all work"
