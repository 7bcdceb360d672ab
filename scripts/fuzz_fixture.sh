#!/usr/bin/env bash
# Regenerates what the checkpoint and resume fuzz harnesses start from, after a change of the
# checkpoint format: the run directory fuzz/fixtures/resume/ (a run of the harnesses' scene,
# checkpoint_scene() in fuzz/harnesses.hpp, killed after a checkpoint of its jammed phase) and the
# seeds fuzz/corpus/{checkpoint,resume}/{unjammed,jammed}.txt (its first checkpoint before jamming,
# and the one the fixture holds).
#   bash scripts/fuzz_fixture.sh [BUDJAM]   (default build/budjam)
set -euo pipefail
cd "$(dirname "$0")/.."
budjam=${1:-build/budjam}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp fuzz/fixtures/resume/scene.toml "$work/scene.toml"
"$budjam" grow "$work/scene.toml" --out "$work/run" --quiet &
pid=$!
# The run goes on in short bursts between SIGSTOP and SIGCONT, and its checkpoint is read while it
# is stopped: so a checkpoint and the logs beside it belong to one moment, as a kill leaves them, and
# the moment a checkpoint of each phase is written is not missed.
phase() {  # the phase on the checkpoint's `state` line (its fifth), or nothing
  local lines=()
  [[ -f $work/run/checkpoint.txt ]] && mapfile -n 5 -t lines < "$work/run/checkpoint.txt"
  local state=${lines[4]:-}
  [[ $state == state\ * ]] && { state=${state#state }; echo "${state%% *}"; }
}
wait_for() {  # wait_for PHASE: returns with the run stopped at a checkpoint of PHASE
  while true; do
    kill -STOP $pid 2>/dev/null || { echo "fuzz_fixture: the run ended before a checkpoint while $1" >&2; exit 1; }
    [[ $(phase) == "$1" ]] && return
    kill -CONT $pid
    read -r -t 0.002 <> <(:) || true
  done
}
wait_for unjammed
cp "$work/run/checkpoint.txt" "$work/unjammed.txt"
kill -CONT $pid
wait_for jammed
rm -rf fuzz/fixtures/resume.new
mkdir -p fuzz/fixtures/resume.new/packings
cp "$work/run/checkpoint.txt" "$work/run/scene.toml" "$work/run/"*.partial fuzz/fixtures/resume.new/
cp "$work/run/packings/"*.pack fuzz/fixtures/resume.new/packings/
kill -KILL $pid
{ wait $pid; } 2>/dev/null || true
rm -rf fuzz/fixtures/resume
mv fuzz/fixtures/resume.new fuzz/fixtures/resume
for corpus in checkpoint resume; do
  cp "$work/unjammed.txt" "fuzz/corpus/$corpus/unjammed.txt"
  cp fuzz/fixtures/resume/checkpoint.txt "fuzz/corpus/$corpus/jammed.txt"
done
echo "fuzz_fixture: $(grep -c . fuzz/fixtures/resume/steps.csv.partial) rows of steps.csv;" \
     "checkpoint at $(sed -n 's/^state \([a-z]*\) [^ ]* [^ ]* [^ ]* \([0-9]*\) .*/\1, step \2/p' fuzz/fixtures/resume/checkpoint.txt)" >&2
