#!/usr/bin/env bash
# Regenerates RELIABILITY.md (issue 18): runs every fault and hostile-input check and writes, per
# check, what was tried, the fault injected or load held, the outcome measured and the data lost.
#   - fuzzing: scripts/fuzz.sh (FUZZ_MODE=--ci by default, --long for 10^6 per target), its summary
#   - real processes and loopback servers: the GoogleTest cases named below, from build/ (Release),
#     with the figures they print, and bench/mixed_load.sh (MIXED_DURATION seconds, default 60; its
#     10 s variant is the ctest MixedLoad.Short)
# Usage: scripts/reliability.sh [OUT.md]   (default RELIABILITY.md; needs build/ built, ../shared/scenes)
#   ONLY=REGEX runs only the checks whose name matches (and no fuzzing): to refresh one row, write to
#   another file and copy the row over.
# Exit 1 when any check fails (the report is still written, with the failing rows marked).
set -uo pipefail
cd "$(dirname "$0")/.."
out="${1:-RELIABILITY.md}"
fuzz_mode="${FUZZ_MODE:---ci}"
mixed_duration="${MIXED_DURATION:-60}"
work=build/reliability
mkdir -p "$work"
failed=0

# name | binary (or a bench/*.sh script) | gtest filter (or the script's environment) | what is tried |
# fault / load | data lost when it passes
checks=(
  # First: the load line measures the machine too, and the other checks leave it busy for a while.
  "Keep-alive clients beyond the threads|bench/server_load.sh|ROUNDS=3 DURATION=5 CHECK_P99_MS=10|wrk on 2 and on 64 keep-alive connections (max_connections), alternated over 3 rounds of 5 s: point GETs at random points of bunny's box and raw tile GETs (~400 kB each); then 100k-point binary batches and 62 slow clients|2 server threads, wrk on the same 2 cores|none: no errors; at 64 connections p99 < 10 ms and req/s at least 2 connections' (medians)"
  "SIGKILL during build, resume|test_faults|Faults.SigkillAtTwentyRandomMomentsThenResumeStoresExactlyTheCleanBuild|terragen 1024² in 64² tiles, raw+mh+mmh+dagmh, 2 threads|20 SIGKILLs at uniform random moments in [0, clean/2] of each run (scene load, ray casting, encoding, commits, merge); each killed store opened|none: tiles, top, preview, tileinfo byte-identical to an uninterrupted build"
  "SIGKILL during merge, resume|test_shard_merge|ShardMerge.SigkillAtTwentyRandomMomentsThenResumeEqualsTheOneMachineBuild|4 shard stores of fzk_haus 4096² (512² tiles, raw+mh+mmh+dagmh) merged in 1 MiB transactions|20 SIGKILLs at uniform random moments in [0, clean] of fresh and resumed merges; each killed store opened|none: the resumed merge equals the one-machine build (every blob, info, progress record and top tree byte-identical)"
  "Disk full|test_faults|Faults.DiskFullBuildExitsOneAndResumesWhenSpaceIsBack|the same build into a tmpfs of half the store's size (private mount namespace)|ENOSPC / short write mid-build; then the tmpfs is grown and the same command rerun|none: exit 1 with 'the disk is full', inspect reads the incomplete store, the resume is byte-identical"
  "Swap of builds under load|test_serve_process|ServerReload.SwapUnderLoadLosesNoRequestAndNeverMixesBuilds:ServerReload.SighupToTheServeProcessSwapsUnderLoadLosingNothing|4 keep-alive clients sending 512-point binary batches without pause, to an in-process server and to a real shadowtiles serve process|store symlink repointed (ln -sfn) mid-load, then Server::reload, or kill -HUP to the serve process|0 requests lost, 0 batches mixing builds (X-Shadowtiles-Build names the answering build)"
  "Mixed load|bench/mixed_load.sh|DURATION=$mixed_duration|wrk with valid requests (point and PCF GETs, tile GETs, JSON batches, every method) on 32 keep-alive connections, beside 4 hostile clients: malformed request lines and query strings, bad and deep JSON, garbage and NaN binary batches, oversized Content-Length, chunked bodies, header floods, stalled bodies, trickled headers, hang-ups|$mixed_duration s of both at once on 2 server threads, the tile cache (4 MiB) evicting all through|none: 0 crashes, 0 5xx, every hostile request a 4xx in time, sampled answers equal to the decoder's, RSS at the end within 10 % of RSS once the cache filled"
  "Slow clients|test_server_limits|ServerLimitsTest.SlowClientsNeverStarveQueries|/healthz and point queries|max_connections - 2 connections that send a partial request and stall|none: queries answer well inside the read timeout"
  "Oversized, chunked and costly requests|test_server_limits|ServerLimitsTest.OversizedBodiesAreRefusedAtOnce:ServerLimitsTest.BatchesAreAdmittedByCost:ServerLimitsTest.FullServerAnswers503AtOnce:ServerLimitsTest.PerAddressCap|declared Content-Length over the limit, chunked bodies, batches over max_batch_cost, a full server, one address over its cap|hostile clients|none: 413 / 411 / 503 at once, never a hang"
  "Hostile requests|test_server|ServerTest.EveryBadInputGetsA4xxAndTheServerKeepsAnswering|malformed query strings, JSON and binary batches, URLs, methods|each request once, then normal queries|none: every one a 4xx with a JSON error, no 5xx"
  "Corrupt stored blobs|test_server_damaged_store|DamagedStoreTest.CorruptBlobIsNeverServedAndHealthWaitsForTheStore|a tile blob with a flipped byte in the store|served over HTTP|never served: 500 corrupt_data, counted in /metrics"
  "Bit flips in blobs and payloads|test_blob|Blob.EveryHeaderBitFlipIsAnError:Blob.PayloadBitFlipsAreErrors|every header bit, payload bits of real-size blobs|single bit flips|every flip detected (checksum)"
  "Bit flips in decoded payloads|test_mh_robustness|MhRobustness.*|every single bit of MH/MMH payloads, random multi-byte corruption|flips past the checksum (the decoder alone)|refused or answers in bounds, never a crash"
  "Raw tile header|test_raw_tile|RawTile.*|magic, version, reserved bits, size, NaN/inf texels|corrupt raw payloads|every one refused (corrupt_data / unsupported)"
  "Malformed scenes|test_scene_loader|SceneLoaderErrors.*|truncated PLY at every length, hostile glTF, bad Terragen files|malformed files|a clear invalid_input error, no hang"
  "Hostile PLY/OFF files|test_mesh_file_prechecks|MeshFilePrechecks.*|element and list counts beyond the file (binary and ascii), short bodies, ascii lines short of a coordinate, OFF indices out of range, control bytes and unknown lines in headers, element names starting with digits, elements assimp does not know, properties after a comment inside an element, \\r/\\f inside lines and backslash continuations (each found by fuzz_scene_loader, the truncation tests or a review against libassimp)|files that made assimp 5.2 hang, allocate 21-64 GB or read out of bounds|none: refused before assimp parses them, with the rule that failed"
)

log_of() { echo "$work/$(basename "$1").$(echo "$2" | tr -c 'a-zA-Z0-9' _).log"; }

run_check() {
  local name=$1 binary=$2 filter=$3 log
  log=$(log_of "$binary" "$name")
  if [[ $binary == *.sh ]]; then
    # A script check: one run, passing when the script exits 0.
    env $filter nice -n 5 bash "$binary" build > "$log" 2>&1 && echo "[       OK ] $binary" >> "$log"
    return
  fi
  if [ ! -x "build/tests/$binary" ]; then echo "missing build/tests/$binary" > "$log"; return 1; fi
  nice -n 5 "build/tests/$binary" --gtest_filter="$filter" > "$log" 2>&1
}

rows=()
for check in "${checks[@]}"; do
  IFS='|' read -r name binary filter tried fault lost <<< "$check"
  [ -n "${ONLY:-}" ] && ! [[ $name =~ $ONLY ]] && continue
  start=$(date +%s)
  if run_check "$name" "$binary" "$filter"; then result=pass; else result=FAIL; failed=1; lost="see the log"; fi
  log=$(log_of "$binary" "$name")
  tests=$(grep -c '^\[       OK \]' "$log" || true)
  # A filter that matches no test (a test renamed or moved) is a failure, not a pass.
  if [ "$tests" -eq 0 ]; then result=FAIL; failed=1; lost="no test matched $binary --gtest_filter=$filter"; fi
  figures=$(grep -E '^(SIGKILL|merge SIGKILL|swap under load[^:]*|slow clients held|mixed load|keep-alive load):' "$log" | tr '\n' ' ' | sed 's/ *$//')
  rows+=("| $name | $tried | $fault | $result ($tests tests, $(( $(date +%s) - start )) s) | ${figures:--} | $lost |")
  echo "$name: $result"
done

# A fuzz.sh summary (its "# ..." line: mode, date, commit, jobs, load; then one row per target) as a
# table; fuzz/long-run.tsv rows carry their own run's date, commit, load and jobs. Executions per
# CPU-second (user + sys of the target's process) are what a target costs; execs/s depend on the load.
fuzz_table() {
  local file=$1
  if [ ! -f "$file" ]; then echo; echo "(no run recorded: $file is missing)"; return; fi
  echo
  if grep -q '^# ' "$file"; then sed -n 's/^# /Run: /p' "$file" | head -1; echo; fi
  echo "| target | executions asked | executions | seconds | execs/s | execs per CPU-s | crashes | peak RSS MiB | run (UTC, commit, load before / after, jobs) |"
  echo "|---|---|---|---|---|---|---|---|---|"
  grep -v '^#' "$file" | tail -n +2 | while IFS=$'\t' read -r target asked runs seconds rate crashes rss cpu when commit load jobs; do
    note=""
    [ "${runs:-0}" -lt "${asked:-0}" ] && note=" (short)"
    per_cpu=$(awk -v r="${runs:-0}" -v c="${cpu:-0}" 'BEGIN { if (c + 0 > 0) printf "%.0f", r / c; else print "-" }')
    run="this run"
    [ -n "${when:-}" ] && run="$when, $commit, $load, $jobs jobs"
    echo "| \`$target\` | $asked | $runs$note | $seconds | $rate | $per_cpu | $crashes | $rss | $run |"
  done
}

fuzz_log="$work/fuzz.log"
if [ -n "${ONLY:-}" ]; then fuzz_result="not run (ONLY=$ONLY)"
elif bash scripts/fuzz.sh "$fuzz_mode" > "$fuzz_log" 2>&1; then fuzz_result=pass; else fuzz_result=FAIL; failed=1; fi
echo "fuzzing ($fuzz_mode): $fuzz_result"
summary=build-fuzz/fuzz-work/summary.tsv

{
  echo "# Reliability"
  echo
  echo "Generated by \`bash scripts/reliability.sh\` on $(date -u +%Y-%m-%d) (commit $(git rev-parse --short HEAD),"
  echo "load average $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores: execution rates are this machine's, shared)."
  echo "Every row is a check that can fail; \"data lost\" is what the check proves stays intact."
  echo
  echo "## Faults, hostile clients and corrupt data"
  echo
  echo "| check | inputs tried | fault injected / load held | result | measured | data lost |"
  echo "|---|---|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "## Fuzzing (libFuzzer, ASan + UBSan; fuzz/README.md)"
  echo
  echo "Seeds from real builds of the shared scenes; committed crash inputs (fuzz/regressions) replayed"
  echo "first. A run stopped by its time cap before its count is marked short."
  echo
  echo "This run (\`scripts/fuzz.sh $fuzz_mode\`): $fuzz_result."
  if [ -z "${ONLY:-}" ]; then fuzz_table "$summary"; fi
  echo
  if [ "$fuzz_mode" != --long ]; then
    echo "Long mode: each target's last \`scripts/fuzz.sh --long\` run (10^6 executions asked), as recorded in"
    echo "fuzz/long-run.tsv by that run."
    fuzz_table fuzz/long-run.tsv
    echo
  fi
  echo "Crashes found by fuzzing and fixed, each with a regression input replayed by every run and a unit"
  echo "test: $(sed -n '/^## Crashes found and fixed/,/^## [^C]/p' fuzz/README.md | grep -c '^| \`fuzz_') (fuzz/README.md, \"Crashes found and fixed\")."
} > "$out"
echo "wrote $out"
exit $failed
