#!/usr/bin/env bash
# Integration test on a real Slurm (issue 16): starts munged, slurmctld and slurmd (Debian 12
# packages, one node on loopback, config below), runs a 4-task shard array of fzk_haus at 8192²
# plus an afterok merge, with one task killed midway: the merge must never run; the killed task is
# resubmitted alone (it resumes its local store), then a new merge, whose store must equal a
# one-machine build tile for tile (shadowtiles-store-diff below: every database byte for byte,
# meta except timings). Stops every daemon it started. Exit 77 (ctest: skipped) when Slurm cannot
# start, except under CI=true, where that fails.
# Usage: slurm_array_test.sh SHADOWTILES_BINARY SOURCE_DIR
set -uo pipefail
bin=$1
src=$2
scene=$src/../shared/scenes/fzk_haus/fzk_haus.obj
args="--up y --sun 135,45 --resolution 8192 --tile 1024 --method mh,mmh,dagmh"
t=$(mktemp -d /tmp/st-slurm.XXXXXX)
pids=()
skip_or_fail() {
  echo "slurm test: $1" >&2
  if [ "${CI:-}" = "true" ]; then echo "FAIL (CI=true: Slurm must start)" >&2; exit 1; fi
  echo "SKIPPED: $1" >&2
  exit 77
}
cleanup() {
  [ -n "${SLURM_CONF:-}" ] && scancel --quiet -u root >/dev/null 2>&1
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  [ -f "$t/slurmd.pid" ] && kill "$(cat "$t/slurmd.pid")" 2>/dev/null
  [ -f "$t/slurmctld.pid" ] && kill "$(cat "$t/slurmctld.pid")" 2>/dev/null
  [ -f "$t/munged.pid" ] && kill "$(cat "$t/munged.pid")" 2>/dev/null
  sleep 1
  rm -rf "$t"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; for f in "$t"/*.log "$t"/results/*.out; do [ -f "$f" ] && { echo "== $f"; tail -20 "$f"; }; done >&2; exit 1; }

for tool in munged slurmctld slurmd sbatch sinfo mdb_copy; do
  command -v "$tool" >/dev/null || skip_or_fail "$tool not installed (scripts/install-deps.sh installs it)"
done
[ "$(id -u)" -eq 0 ] || skip_or_fail "needs root (SlurmUser=root, munged)"

# munge: own key, socket, state (socket dir mode 0755 so job steps reach it).
mkdir -p "$t/munge" "$t/state" "$t/spool" "$t/results"
chmod 0755 "$t/munge"
dd if=/dev/urandom of="$t/munge.key" bs=1024 count=1 2>/dev/null
chmod 0400 "$t/munge.key"
munged --force -S "$t/munge/munge.socket" --key-file="$t/munge.key" --pid-file="$t/munged.pid" \
  --log-file="$t/munged.log" --seed-file="$t/munge.seed" || skip_or_fail "munged did not start"
host=$(hostname -s)
port=$((17000 + RANDOM % 2000))
cat > "$t/slurm.conf" <<CONF
ClusterName=shadowtiles-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$t/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$t/state
SlurmdSpoolDir=$t/spool
SlurmctldPidFile=$t/slurmctld.pid
SlurmdPidFile=$t/slurmd.pid
SlurmctldLogFile=$t/slurmctld.log
SlurmdLogFile=$t/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
MinJobAge=600
NodeName=$host NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$t/slurm.conf
slurmctld -i -f "$SLURM_CONF" || skip_or_fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" || skip_or_fail "slurmd did not start"
state=""
for _ in $(seq 1 60); do
  state=$(sinfo -h -N -o %t 2>/dev/null | head -n 1)
  [ "$state" = "idle" ] && break
  sleep 0.5
done
[ "$state" = "idle" ] || { tail -5 "$t/slurmctld.log" "$t/slurmd.log" >&2; skip_or_fail "node not idle after 30 s (state '$state')"; }
echo "slurm up: node $host idle"

# The one-machine build the array must equal (run while the daemons idle).
# shellcheck disable=SC2086
"$bin" build "$scene" --out "$t/single" -j 2 $args >/dev/null 2>"$t/single.log" || fail "one-machine build"

export SHADOWTILES=$bin SCENE=$scene SHARDS=4 RESULTS=$t/results OUT=$t/final BUILD_ARGS=$args SCRATCH=$t/scratch
mkdir -p "$SCRATCH"
job_state() { scontrol show job "$1" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | head -n 1; }

# Round 1: task 2 dies after 3 tiles. `sbatch --wait` on the array must return its failure, and the
# afterok merge must never run.
KILL_TASK=2 KILL_AFTER_TILES=3 sbatch --parsable --wait --array=0-3 --chdir="$RESULTS" --export=ALL \
  "$src/scripts/slurm/build_shards.sbatch" > "$t/array.id" 2>"$t/array.err" &
waiter=$!
pids+=("$waiter")
for _ in $(seq 1 100); do [ -s "$t/array.id" ] && break; sleep 0.1; done
array=$(head -n 1 "$t/array.id"); array=${array%%;*}
[ -n "$array" ] || fail "array not submitted: $(cat "$t/array.err")"
merge=$(sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes --chdir="$RESULTS" --export=ALL \
  "$src/scripts/slurm/merge.sbatch") || fail "merge submit"
merge=${merge%%;*}
echo "array $array, merge $merge (afterok)"
wait "$waiter"
array_rc=$?
echo "sbatch --wait on the array returned $array_rc"
[ "$array_rc" -ne 0 ] || fail "sbatch --wait returned 0 although task 2 was killed"
task2=$(job_state "${array}_2")
echo "task 2: $task2"
[ "$task2" = "JobState=FAILED" ] || fail "killed task 2 ended as '$task2', expected FAILED"
for i in 0 1 3; do [ -f "$t/results/shard$i/data.mdb" ] || fail "shard $i not copied to results"; done
[ ! -e "$t/results/shard2" ] || fail "a killed shard must leave no result"
merge_state=""
for _ in $(seq 1 50); do
  merge_state=$(job_state "$merge")
  [ "$merge_state" = "JobState=CANCELLED" ] && break
  sleep 0.2
done
echo "merge after the failed array: $merge_state"
[ "$merge_state" = "JobState=CANCELLED" ] || fail "afterok merge not cancelled after the failed array: '$merge_state'"
[ ! -e "$t/final" ] || fail "the afterok merge ran although a shard failed"
ls -d "$SCRATCH"/shadowtiles-*-shard2 >/dev/null 2>&1 || fail "the killed shard left no local store to resume"

# Round 2: re-run task 2 alone (it resumes its local store) and a new merge after it, the way
# docs/scale-out.md says: ARRAY=2 WAIT=1 scripts/slurm/submit.sh, which returns the merge's status.
ARRAY=2 WAIT=1 "$src/scripts/slurm/submit.sh" > "$t/submit2.out" 2>&1 || fail "re-run + merge failed: $(cat "$t/submit2.out")"
array2=$(head -n 1 "$t/submit2.out")
resumed=$(cat "$t/results/shadowtiles-shard-${array2}_2.out" 2>/dev/null)
grep -Eq "[1-9][0-9]* already committed" <<<"$resumed" || fail "re-run task $array2 did not resume its local store"
[ -f "$t/final/data.mdb" ] || fail "merge produced no store"
"$bin" store-diff "$t/final" "$t/single" || fail "merged store differs from the one-machine build"
echo "PASS: Slurm array (one task killed, resubmitted) + afterok merge equals the one-machine build"
