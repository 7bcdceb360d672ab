#!/usr/bin/env bash
# ctest demo_builds_only_budjam_and_the_module: the CMake options of `bootstrap.sh demo` give a
# build whose default target holds budjam, its man page and the Python module and none of the test
# programs, the test support library or the benchmarks (those are what made the demo slow), and
# whose libraries and executable are compiled in unity batches (half the CPU time).
#   bash tests/install/test_demo_build.sh SOURCE_DIR WORK_DIR
set -euo pipefail
source=$1 work=$2
fail() { echo "test_demo_build: $*" >&2; exit 1; }

eval "$(grep '^demo_options=' "$source/scripts/bootstrap.sh")"
[[ ${#demo_options[@]} -gt 0 ]] || fail "no demo_options=(...) in scripts/bootstrap.sh"
rm -rf "$work"
cmake -S "$source" -B "$work" -DCMAKE_BUILD_TYPE=Release "${demo_options[@]}" >/dev/null
targets=$(cmake --build "$work" --target help | awk '/^\.\.\. / { print $2 }')
for wanted in budjam budjam_python; do
  grep -qx "$wanted" <<<"$targets" || fail "the demo build has no target $wanted"
done
unwanted=$(grep -E '^(test_|bench_|budjam_test_support$|budjam_catch_main$|rigidity_speed$)' <<<"$targets" || true)
[[ -z $unwanted ]] || fail "the demo build also builds: $(tr '\n' ' ' <<<"$unwanted")"
for target in budjam_core budjam_io budjam_analysis budjam; do
  [[ -f $work/CMakeFiles/$target.dir/Unity/unity_0_cxx.cxx ]] || fail "the demo build compiles $target source by source"
done
echo "test_demo_build: the demo builds budjam and the Python module only, in unity batches"
