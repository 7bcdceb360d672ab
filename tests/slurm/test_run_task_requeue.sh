#!/usr/bin/env bash
# ctest slurm_task_requeues_before_the_limit: scripts/slurm/run_task.sh, told by USR1 that the time
# limit is near, stops its run with SIGTERM and requeues the task (a stand-in for scontrol), also
# when the run does not stop (a grow inside a long trial ignores the signal until the trial ends):
# then after half of SLURM_GRACE, not at the limit. No Slurm needed.
#   bash tests/slurm/test_run_task_requeue.sh SOURCE_DIR
set -euo pipefail
source=$1
work=$(mktemp -d)
pids=()
trap 'kill -KILL "${pids[@]}" 2>/dev/null; rm -rf "$work"' EXIT
fail() { echo "test_run_task_requeue: $*" >&2; exit 1; }
mkdir -p "$work/bin"
cat >"$work/bin/scontrol" <<'FAKE'
#!/usr/bin/env bash
echo "$*" >>"$SCONTROL_LOG"
FAKE
# A run that stops at SIGTERM, and one that ignores it for a minute.
cat >"$work/stops.sh" <<'RUN'
#!/usr/bin/env bash
echo "$$" >"$PID_FILE"
exec sleep 60
RUN
cat >"$work/ignores.sh" <<'RUN'
#!/usr/bin/env bash
trap '' TERM
echo "$$" >"$PID_FILE"
exec sleep 60
RUN
chmod +x "$work/bin/scontrol" "$work/stops.sh" "$work/ignores.sh"
echo "$work/run" >"$work/runs.txt"

# Starts the task with RUN as its make command, sends USR1 once the run is up; checks the task's
# status and the requeue, and sets `elapsed` to the seconds from the signal to the task's end.
task() {
  local run=$1 log=$work/scontrol_$1.log
  export PATH="$work/bin:$PATH" SCONTROL_LOG=$log PID_FILE=$work/pid_$1 SLURM_ARRAY_JOB_ID=7 \
    SLURM_ARRAY_TASK_ID=0 SLURM_GRACE=4
  bash "$source/scripts/slurm/run_task.sh" "$work/runs.txt" "$work/$run.sh" "summary.json" 2>"$work/$run.err" &
  local pid=$!
  local k=0
  while [[ ! -s $PID_FILE ]] && ((k++ < 500)); do sleep 0.01; done
  [[ -s $PID_FILE ]] || fail "$run: the run did not start"
  pids+=("$(cat "$PID_FILE")")
  local t0=$SECONDS rc=0
  kill -USR1 "$pid"
  wait "$pid" || rc=$?
  ((rc == 0)) || fail "$run: the task exited $rc, not 0 (requeued)"
  [[ $(cat "$log" 2>/dev/null) == "requeue 7_0" ]] || fail "$run: scontrol was not asked to requeue 7_0 (got '$(cat "$log" 2>/dev/null)')"
  elapsed=$((SECONDS - t0))
}

task stops
((elapsed <= 1)) || fail "a run that stops at SIGTERM was requeued only after $elapsed s"
task ignores
((elapsed >= 2 && elapsed <= 3)) ||
  fail "a run that ignores SIGTERM was requeued after $elapsed s (expected SLURM_GRACE / 2 = 2)"
grep -q "did not stop within" "$work/ignores.err" || fail "no notice that the run did not stop"
echo "test_run_task_requeue: requeued at once, and after SLURM_GRACE / 2 when the run did not stop"
