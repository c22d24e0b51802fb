#!/usr/bin/env bash
# Runs every libFuzzer target (fuzz/, see fuzz/README.md) under ASan + UBSan, seeded from real builds
# of the shared scenes (scripts/fuzz_corpus.py), after replaying the committed crash regressions
# (fuzz/regressions/<target>/*).
# Usage: scripts/fuzz.sh [--ci | --long] [--runs N] [--time S] [--jobs J] [--seed S] [--work DIR] [--no-build] [TARGET...]
#   --ci     (default) 100,000 executions per target, seeded (-seed=1: CI sees the same mutations on
#            every run, so a CI failure reproduces and a green CI is not luck; --long explores), each
#            target capped at --time 290 s and all of them at --budget 300 s (a target starting late
#            gets what is left of it: regressions + fuzzing end within ~5 min on 2 cores; the slowest,
#            fuzz_scene_loader, needs ~180 CPU-s for its count); CI runs this
#   --long   1,000,000 executions per target, each capped at 3 h (ctest label `long`: fuzz_long);
#            it also records each target's row in fuzz/long-run.tsv (committed: RELIABILITY.md shows
#            the last long run of every target beside the CI run), with its date, commit and load
#   --budget seconds for all targets' fuzzing together (0: none, the --long default)
#   --jobs   targets fuzzed at once (default 2, the CI machine's cores)
#   --seed   libFuzzer's -seed (default: 1 in --ci mode, random in --long mode)
#   --work   working directory (default build-fuzz/fuzz-work; a second run beside a long one needs its own)
#   --no-build  use build/ and build-fuzz/ as they are (a run beside a build in progress)
# Builds what it needs: the Release CLI in build/ (for the seed stores) when missing, the fuzz
# targets in build-fuzz/ (clang, -DSHADOWTILES_FUZZ=ON, assertions on).
# Writes build-fuzz/fuzz-work/summary.tsv (target, runs asked, runs done, seconds, execs/s, crashes,
# peak RSS MiB, CPU seconds), which RELIABILITY.md reads. Exit 0 when no target crashed, 1 when one did (its
# input is kept in build-fuzz/fuzz-work/artifacts and its log printed). A target that reaches its
# time cap before its count (a loaded machine) is reported as short, not failed.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
mode=ci
runs=
max_time=290
budget=300
jobs=2
seed=
work=
build=yes
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --ci) mode=ci; max_time=290; budget=300 ;;
    --seed) seed="$2"; shift ;;
    --long) mode=long; max_time=10800; budget=0 ;;
    --runs) runs="$2"; shift ;;
    --time) max_time="$2"; shift ;;
    --budget) budget="$2"; shift ;;
    --jobs) jobs="$2"; shift ;;
    --work) work="$2"; shift ;;
    --no-build) build=no ;;
    -h|--help) sed -n '2,23p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1") ;;
  esac
  shift
done
# Slowest first (per execution), so the last targets to run are short ones and the jobs end together.
all_targets=(fuzz_scene_loader fuzz_http fuzz_tile_mh fuzz_tile_mmh fuzz_store_meta fuzz_tile_cpvs fuzz_tile_raw
             fuzz_tile_dagmh fuzz_tile_sst fuzz_request_parsing fuzz_preview fuzz_blob)
[ ${#targets[@]} -eq 0 ] && targets=("${all_targets[@]}")

start=$(date +%s)
if [ "$build" = yes ]; then
  if [ ! -x build/cli/shadowtiles ]; then
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
    cmake --build build --target shadowtiles
  fi
  launcher=()
  command -v ccache > /dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS=-O1 -DCMAKE_C_FLAGS=-O1 \
    -DSHADOWTILES_FUZZ=ON -DSHADOWTILES_BUILD_TESTS=OFF -DSHADOWTILES_BUILD_BENCH=OFF "${launcher[@]}" > /dev/null
  cmake --build build-fuzz --target "${targets[@]}"
fi
built=$(date +%s)

work=$(realpath -m "${work:-$root/build-fuzz/fuzz-work}")
mkdir -p "$work/artifacts" "$work/logs" "$work/evolved"
store=$(/usr/bin/python3 scripts/fuzz_corpus.py build/cli/shadowtiles "$work" 2> "$work/logs/corpus.log" | tail -1)
seeded=$(date +%s)
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
started_at=$(date -u '+%Y-%m-%d %H:%M')
commit=$(git describe --always --dirty=+changes --exclude='*' 2> /dev/null || echo unknown)  # what the targets were built from
export SHADOWTILES_FUZZ_STORE="$store"
# A 16 MiB quarantine (ASan's default: 256 MiB) still holds every block freed by the last several
# inputs, so a use after free within an input is caught; freed memory is recycled sooner instead of
# every allocation faulting in fresh pages (fuzz_http: 16 % less CPU per execution, 40 % fewer page faults).
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:allocator_may_return_null=1:quarantine_size_mb=16"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

# Executions asked of a target: --runs, else the mode's count.
runs_for() {
  if [ -n "$runs" ]; then echo "$runs"; return; fi
  if [ "$mode" = long ]; then echo 1000000; return; fi
  echo 100000
}

# One target: regressions first (each committed input once), then the fuzzing run.
fuzz_one() {
  local target=$1 want
  want=$(runs_for "$1")
  local exe="$root/build-fuzz/fuzz/$1" log="$work/logs/$1.log" extra=() asan="$ASAN_OPTIONS"
  case "$target" in
    fuzz_http) extra=(-max_len=16384) ;;
    # assimp's PLY importer leaks its parse tree on truncated files (builder/scene_loader.hpp, "Known
    # left"; the leak is allocated inside libassimp's PLY reader): Debian's library, not ours, so
    # leaks are not counted for this target.
    fuzz_scene_loader) extra=(-max_len=65536); asan="${asan/detect_leaks=1/detect_leaks=0}" ;;
  esac
  if [ -d "$root/fuzz/regressions/$target" ] && [ -n "$(ls -A "$root/fuzz/regressions/$target")" ]; then
    if ! ASAN_OPTIONS="$asan" "$exe" "${extra[@]}" "$root/fuzz/regressions/$target"/* > "$work/logs/$target.regressions.log" 2>&1; then
      echo "$target: a committed regression input fails again:"; tail -30 "$work/logs/$target.regressions.log"
      return 1
    fi
  fi
  mkdir -p "$work/evolved/$target"
  local seed_flag=()
  if [ -n "$seed" ]; then seed_flag=(-seed="$seed"); elif [ "$mode" = ci ]; then seed_flag=(-seed=1); fi
  local status=0 t0 cap=$max_time
  t0=$(date +%s)
  # Within the total budget: a target starting late gets what is left (at least 5 s).
  if [ "$budget" -gt 0 ]; then
    local left=$(( seeded + budget - t0 ))
    [ "$left" -lt "$cap" ] && cap=$left
    [ "$cap" -lt 5 ] && cap=5
  fi
  # CPU seconds (user + sys, every thread) besides wall seconds: on a shared machine executions per
  # CPU-second say what a target costs, executions per second mostly say the load.
  local TIMEFORMAT='%U %S'
  { time ASAN_OPTIONS="$asan" nice -n 10 "$exe" -runs="$want" -max_total_time="$cap" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 "${seed_flag[@]}" \
    -artifact_prefix="$work/artifacts/$target-" "${extra[@]}" "$work/evolved/$target" "$work/corpus/$target" \
    > "$log" 2>&1 || status=$?; } 2> "$work/logs/$target.cpu"
  local cpu
  cpu=$(awk '{ printf "%.1f", $1 + $2 }' "$work/logs/$target.cpu" 2> /dev/null)
  local done_runs rate rss
  done_runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
  local crashes=0
  [ $status -ne 0 ] && crashes=1
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$target" "$want" "${done_runs:-0}" "$(( $(date +%s) - t0 ))" \
    "${rate:-0}" "$crashes" "${rss:-0}" "${cpu:-0}" > "$work/logs/$target.row"
  if [ $status -ne 0 ]; then
    echo "$target: CRASH (exit $status), input in $work/artifacts:"; grep -v '^#\|^INFO\|^MS:' "$log" | tail -40
    return 1
  fi
  if [ "${done_runs:-0}" -lt "$want" ]; then
    echo "$target: SHORT: ${done_runs:-0} of $want executions within its $cap s cap (${rate:-0}/s), 0 crashes"
    return 0
  fi
  echo "$target: ${done_runs} executions, ${rate}/s, 0 crashes, peak RSS ${rss} MiB"
}

failed=0
running=0
for target in "${targets[@]}"; do
  rm -f "$work/logs/$target.row"
  fuzz_one "$target" &
  running=$((running + 1))
  if [ $running -ge "$jobs" ]; then
    wait -n || failed=1
    running=$((running - 1))
  fi
done
while [ $running -gt 0 ]; do
  wait -n || failed=1
  running=$((running - 1))
done

fuzzed=$(date +%s)
summary="$work/summary.tsv"
{
  # What the rates depend on: the machine is shared, so its load is part of the result.
  printf '# %s mode, %s UTC, commit %s, %s jobs on %s cores (nice 10), load average %s before and %s after, fuzzing %s s\n' \
    "$mode" "$(date -u '+%Y-%m-%d %H:%M')" "$commit" "$jobs" "$(nproc)" \
    "$load_before" "$(cut -d' ' -f1-3 /proc/loadavg)" "$((fuzzed - seeded))"
  printf 'target\truns_asked\truns\tseconds\texecs_per_s\tcrashes\tpeak_rss_mb\tcpu_s\n'
  for target in "${targets[@]}"; do
    cat "$work/logs/$target.row" 2> /dev/null || printf '%s\t%s\t0\t0\t0\t1\t0\t0\n' "$target" "$(runs_for "$target")"
  done
} > "$summary"
# Long runs are kept in the repository (RELIABILITY.md shows them beside the CI run): each target's
# row of its last long run at the long mode's own count, with that run's date, commit and load (a
# long run of some targets replaces only their rows).
if [ "$mode" = long ] && [ -z "$runs" ]; then
  record="$root/fuzz/long-run.tsv"
  stamp="$started_at	$commit	$load_before / $(cut -d' ' -f1-3 /proc/loadavg)	$jobs"
  {
    printf 'target\truns_asked\truns\tseconds\texecs_per_s\tcrashes\tpeak_rss_mb\tcpu_s\tstarted_utc\tcommit\tload_before_after\tjobs\n'
    for target in "${all_targets[@]}"; do
      if [[ " ${targets[*]} " == *" $target "* ]]; then
        printf '%s\t%s\n' "$(grep -P "^$target\t" "$summary")" "$stamp"
      elif [ -f "$record" ]; then
        grep -P "^$target\t" "$record" || true
      fi
    done
  } > "$record.new"
  mv "$record.new" "$record"
fi
echo "fuzz.sh: ${#targets[@]} targets ($mode mode, each capped at ${max_time} s, ${budget} s in all (0: no total cap)), build $((built - start)) s, corpus $((seeded - built)) s, regressions + fuzzing $((fuzzed - seeded)) s (load average $load_before before); summary in $summary"
exit $failed
