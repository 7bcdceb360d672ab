#!/usr/bin/env bash
# ctest slurm_wait_reports_the_failed_job: scripts/slurm/submit_sweep.sh against a stand-in for
# sbatch and squeue that runs each job at once on this machine (array tasks in order, the dependent
# job only if they all succeeded). Without SLURM_WAIT the script says how to follow the jobs; with
# SLURM_WAIT=1 it exits with the sweep's status, and when a run fails it prints the end of that
# run's log. No Slurm needed.
#   bash tests/slurm/test_slurm_wait_reports.sh SOURCE_DIR
set -euo pipefail
source=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "test_slurm_wait_reports: $*" >&2; exit 1; }
mkdir -p "$work/bin" "$work/state"

cat >"$work/bin/sbatch" <<'FAKE'
#!/usr/bin/env bash
# sbatch --parsable [--array=0-K] [--dependency=afterok:ID] --output=PATTERN ... SCRIPT ARGS...
ids=$FAKE_SLURM/next_id; id=$(( $(cat "$ids" 2>/dev/null || echo 100) + 1 )); echo "$id" >"$ids"
array= after= output=
while [[ $1 == -* ]]; do
  case $1 in
    --array=*) array=${1#--array=}; array=${array%%%*} ;;
    --dependency=afterok:*) after=${1#--dependency=afterok:} ;;
    --output=*) output=${1#--output=} ;;
  esac
  shift
done
if [[ -n $after ]] && grep -qv '^0$' "$FAKE_SLURM/status_$after"; then echo "$id"; exit 0; fi  # cancelled
if [[ -n $array ]]; then
  for ((t = ${array%-*}; t <= ${array#*-}; t++)); do
    log=${output//%A/$id}; log=${log//%a/$t}
    SLURM_ARRAY_JOB_ID=$id SLURM_ARRAY_TASK_ID=$t bash "$@" >>"$log" 2>&1; echo $? >>"$FAKE_SLURM/status_$id"
  done
else
  SLURM_JOB_ID=$id bash "$@" >"${output//%j/$id}" 2>&1; echo $? >"$FAKE_SLURM/status_$id"
fi
echo "$id"
FAKE
printf '#!/usr/bin/env bash\nexit 0\n' >"$work/bin/squeue"  # every job has ended when sbatch returns
# A "make" that fails for the run named "broken" and succeeds for everything else.
cat >"$work/fake_make" <<'FAKE'
#!/usr/bin/env bash
for target in "$@"; do
  [[ $target == broken/* ]] && { echo "building $target"; echo "budjam: error: the broken run failed"; exit 2; }
done
echo "made $*"
FAKE
chmod +x "$work/bin/sbatch" "$work/bin/squeue" "$work/fake_make"
export PATH=$work/bin:$PATH FAKE_SLURM=$work

sweep() {  # sweep RUN... : submits the runs; prints stderr, returns the status
  local state=$work/state/$1
  mkdir -p "$state"
  printf '%s\n' "$@" >"$state/runs.txt"
  bash "$source/scripts/slurm/submit_sweep.sh" "$state" "$work/fake_make" "summary.json" analysis 2>&1 >/dev/null
}

out=$(SLURM_WAIT=0 sweep good1 good2) || fail "a submitted sweep without SLURM_WAIT exited non-zero"
grep -q "not waiting; follow with: squeue -j" <<<"$out" || fail "no line saying how to follow the jobs: $out"

out=$(SLURM_WAIT=1 sweep good3 good4) || fail "a successful sweep with SLURM_WAIT=1 exited non-zero: $out"

if out=$(SLURM_WAIT=1 sweep good5 broken); then fail "a sweep with a failed run exited 0"; fi
grep -q "run-.*_1.log (exit 2) ends with:" <<<"$out" || fail "the failed task's log is not named: $out"
grep -q "  budjam: error: the broken run failed" <<<"$out" || fail "the failed task's last lines are missing: $out"
grep -q "_0.log" <<<"$out" && fail "the successful task is reported as failed: $out"
echo "test_slurm_wait_reports: the no-wait hint, the wait status and the failed job's log lines are right"
