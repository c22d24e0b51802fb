#!/usr/bin/env python3
"""bench/contract_sizes.py keeps what it did not rerun: a run at one resolution regenerates that
resolution's rows and keeps every other resolution's size rows, error rows and DAG-MH > CPVS lines
verbatim (their runs' JSON is not in the repository), names their sources, and a rerun of the same
files changes nothing. Usage: contract_sizes_test.py PROJECT_SOURCE_DIR"""
import json
import os
import subprocess
import sys
import tempfile

script = os.path.join(sys.argv[1], "bench", "contract_sizes.py")


def run_file(path, resolution, commit, dagmh):
    scenes = []
    for scene in ("fzk_haus", "nefertiti"):
        for contract in ("anywhere", "surfaces"):
            b = {"raw": 1_000_000, "mh": 9000, "mmh": 8000, "dagmh": dagmh, "cpvs": 5000, "sst": 7000}
            acc = {m: {"false_lit": 3, "false_shadowed": 9} for m in b}
            scenes.append({"scene": scene, "resolution": resolution, "receivers": contract,
                           "stats": {"bytes_by_method": b, "wall_over_ray_casting": 2.5},
                           "accuracy": {"receivers": 20000, "methods": acc}})
    with open(path, "w") as f:
        json.dump({"resolution": resolution, "git_commit": commit, "git_dirty": False, "scenes": scenes}, f)


def regenerate(md, *runs, build_time=()):
    cmd = [sys.executable, script, *runs, "--md", md] + (["--build-time", *build_time] if build_time else [])
    subprocess.run(cmd, check=True)
    return open(md).read()


with tempfile.TemporaryDirectory() as tmp:
    os.chdir(tmp)
    os.mkdir("out")
    md = "BENCH.md"
    open(md, "w").write("# Benchmarks\n")
    run_file("out/sizes-4k.json", 4096, "aaaa", dagmh=6000)  # fzk_haus surfaces: DAG-MH > CPVS at 4K
    run_file("out/time-4k.json", 4096, "aaaa", dagmh=6000)
    first = regenerate(md, "out/sizes-4k.json", build_time=["out/time-4k.json"])
    rows_4k = [l for l in first.splitlines() if l.startswith("| ") and " | 4K | " in l]
    assert len(rows_4k) == 8, rows_4k  # 4 size rows, 4 error rows
    assert all(l.endswith("| 2.50 |") for l in rows_4k if l.count("|") == 14), rows_4k  # timed: no '*'
    assert "- 4K, `surfaces`, open scenes where DAG-MH is larger than CPVS: fzk_haus 1.20" in first, first

    run_file("out/sizes-64k.json", 65536, "bbbb", dagmh=4000)
    second = regenerate(md, "out/sizes-64k.json")
    for row in rows_4k:
        assert row in second, f"4K row lost or changed: {row}"
    assert "- 4K, `surfaces`, open scenes where DAG-MH is larger than CPVS: fzk_haus 1.20" in second, second
    assert "- 64K, `surfaces`, open scenes where DAG-MH is larger than CPVS: none (of fzk_haus)" in second, second
    assert "previous regeneration (out/sizes-4k.json, out/time-4k.json; commit `aaaa`)" in second, second
    assert len([l for l in second.splitlines() if " | 64K | " in l]) == 8, second
    assert "fzk_haus 4K surfaces" not in second  # no lossless method leaks: nothing listed as worse

    third = regenerate(md, "out/sizes-64k.json")
    assert third == second, "a rerun of the same files changed the report"
print("contract_sizes.py keeps other resolutions: ok")
