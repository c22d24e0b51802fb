#!/usr/bin/env python3
"""bench/contract_sizes.py keeps what it did not rerun: a run regenerates its own (scene, resolution,
contract) rows and keeps every other row verbatim (their runs' JSON is not in the repository): other
resolutions' size rows, error rows and DAG-MH > CPVS lines, and other scenes' rows at a rerun
resolution, which also count in that resolution's DAG-MH > CPVS line. It names their sources, and a
rerun of the same files changes nothing. Usage: contract_sizes_test.py PROJECT_SOURCE_DIR"""
import json
import os
import subprocess
import sys
import tempfile

script = os.path.join(sys.argv[1], "bench", "contract_sizes.py")


def run_file(path, resolution, commit, dagmh, scene_names=("fzk_haus", "nefertiti")):
    scenes = []
    for scene in scene_names:
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

    # One scene rerun at 64K: its rows change, nefertiti's 64K rows and every 4K row stay, and the
    # 64K DAG-MH > CPVS line now names the rerun scene.
    run_file("out/fzk-64k.json", 65536, "cccc", dagmh=5500, scene_names=("fzk_haus",))
    fourth = regenerate(md, "out/fzk-64k.json")
    nefertiti_64k = [l for l in second.splitlines() if l.startswith("| nefertiti |") and " | 64K | " in l]
    assert len(nefertiti_64k) == 4, nefertiti_64k
    for row in rows_4k + nefertiti_64k:
        assert row in fourth, f"row lost or changed: {row}"
    fzk_64k = [l for l in fourth.splitlines() if l.startswith("| fzk_haus |") and " | 64K | " in l]
    assert len(fzk_64k) == 4 and all(l not in second for l in fzk_64k if l.count("|") == 14), fzk_64k
    assert "- 64K, `surfaces`, open scenes where DAG-MH is larger than CPVS: fzk_haus 1.10 (of fzk_haus)" in fourth, fourth
    assert len([l for l in fourth.splitlines() if " | 64K | " in l]) == 8, fourth
    table = [l for l in fourth.splitlines() if l.count("|") == 14 and l.startswith("| ") and "---" not in l
             and not l.startswith("| scene")]
    order = [(int(l.split("|")[3].strip()[:-1]), l.split("|")[1].strip()) for l in table]
    assert order == sorted(order), f"size rows out of (resolution, scene) order: {order}"

    # A build-time run alone (a new tile size, say) updates the wall/rays of kept 4K rows and names
    # its tile; their bytes stay.
    with open("out/time-4k-t2048.json", "w") as f:
        json.dump({"resolution": 4096, "tile": 2048, "git_commit": "dddd", "git_dirty": False,
                   "scenes": [{"scene": "nefertiti", "resolution": 4096, "receivers": "anywhere",
                               "stats": {"bytes_by_method": {}, "wall_over_ray_casting": 1.25}}]}, f)
    fifth = regenerate(md, "out/fzk-64k.json", build_time=["out/time-4k-t2048.json"])
    retimed = [l for l in fifth.splitlines() if l.startswith("| nefertiti |") and " | 4K | anywhere |" in l and l.count("|") == 14]
    assert len(retimed) == 1 and retimed[0].endswith("| 1.25 |"), retimed
    before = [l for l in fourth.splitlines() if l.startswith("| nefertiti |") and " | 4K | anywhere |" in l and l.count("|") == 14]
    assert retimed[0].rsplit("|", 2)[0] == before[0].rsplit("|", 2)[0], (retimed, before)  # bytes unchanged
    assert "those runs in 2048^2 tiles" in fifth, fifth
print("contract_sizes.py keeps the rows it did not rerun: ok")
