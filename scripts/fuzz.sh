#!/usr/bin/env bash
# Runs the libFuzzer harnesses in fuzz/ (ASan + UBSan, clang-14) for a fixed time each:
#   bash scripts/fuzz.sh [SECONDS] [scene|packing|checkpoint|resume|degenerate ...] (default: 60 s, all five)
# The seed corpus is fuzz/corpus/<name>/; new inputs go to build-fuzz/corpus/<name>/, crash and
# hang reproducers to build-fuzz/artifacts/<name>/. Exits 1 if any harness found one.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
names=("$@")
((${#names[@]})) || names=(scene packing checkpoint resume degenerate)

cmake -S . -B build-fuzz -DBUDJAM_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target "${names[@]/#/fuzz_}" >/dev/null

status=0
for n in "${names[@]}"; do
  mkdir -p "build-fuzz/corpus/$n" "build-fuzz/artifacts/$n"
  echo "fuzz: $n for ${seconds}s" >&2
  if ! "build-fuzz/fuzz_$n" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
       -print_final_stats=1 -artifact_prefix="build-fuzz/artifacts/$n/" \
       "build-fuzz/corpus/$n" "fuzz/corpus/$n" 2>"build-fuzz/$n.log"; then
    echo "fuzz: $n FOUND A PROBLEM: see build-fuzz/$n.log and build-fuzz/artifacts/$n/" >&2
    status=1
  fi
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "build-fuzz/$n.log" >&2 || true
done
exit $status
