#!/usr/bin/env bash
# Submits a sharded build: the shard array, then the merge once all shards succeeded (afterok).
#   SHADOWTILES=... SCENE=... SHARDS=16 RESULTS=/shared/run1 OUT=/shared/run1/final \
#   BUILD_ARGS="--resolution 65536 --tile 4096 --method mmh,dagmh --sun 135,45" scripts/slurm/submit.sh
# Prints "<array job id> <merge job id>". Extra sbatch flags (partition, account): SBATCH_FLAGS.
# ARRAY=2,5 re-runs only those tasks (after a failure; finished shards are skipped anyway), then a
# new merge. WAIT=1 blocks until the merge ends (sbatch --wait) and exits with its status: non-zero
# when a shard failed, since the merge is then cancelled (--kill-on-invalid-dep).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
: "${SHADOWTILES:?}" "${SCENE:?}" "${SHARDS:?}" "${RESULTS:?}" "${OUT:?}"
mkdir -p "$RESULTS"
# shellcheck disable=SC2086
array=$(sbatch --parsable ${SBATCH_FLAGS:-} --array="${ARRAY:-0-$((SHARDS - 1))}" --chdir="$RESULTS" --export=ALL \
  "$here/build_shards.sbatch")
array=${array%%;*}
merge_flags=(--parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes --chdir="$RESULTS" --export=ALL)
if [ "${WAIT:-0}" = 1 ]; then
  echo "$array"
  # shellcheck disable=SC2086
  sbatch ${SBATCH_FLAGS:-} "${merge_flags[@]}" --wait "$here/merge.sbatch"
  exit $?
fi
# shellcheck disable=SC2086
merge=$(sbatch ${SBATCH_FLAGS:-} "${merge_flags[@]}" "$here/merge.sbatch")
echo "$array ${merge%%;*}"
