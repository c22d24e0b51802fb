#!/usr/bin/env python3
"""A/B of two builds, alternated on the same scenes, so that a change's effect on build time can be
told from the host's drift (docs/build-time.md: single runs move by 5-10 % on a shared machine).

    python3 bench/build_ab.py --a NEW/shadowtiles --b OLD/shadowtiles --scenes oahu,honolulu --runs 5
    python3 bench/build_ab.py --a build/cli/shadowtiles --b-args="--entry-slack-texels 0" --scenes oahu

A and B are two executables (B defaults to A) and/or two sets of extra build options; each scene
(from --config, with the bench's sun, up axis and heightfields) is built A, B, A, B, ... --runs times
each, from an empty store every time. Per scene it prints:
  - whether the first pair's stores hold the same build (`shadowtiles store-diff`: tiles, tile info,
    previews and top levels byte for byte, the meta equal but for timings; builds are deterministic,
    so one pair tells), and if not, store-diff's first difference and the bytes each side stores;
  - per pair, A's process CPU seconds (user + system) and wall/rays over B's, and their medians
    (below 1: A costs less); pairing keeps a ratio meaningful while the machine's speed drifts;
  - per phase (the build's own thread-second timers), the median of A and of B, and each phase over
    the same run's rays (a phase's share, which the host's speed moves less than its seconds).
With --json FILE the runs' figures are written too (after every scene).
"""
import argparse
import json
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

PHASES = ["rays_thread_sum", "bvh_thread_sum", "entry_rule_thread_sum", "caps_thread_sum", "encode_thread_sum",
          "preview_thread_sum", "store_thread_sum"]


def build_command(cli, extra, scene, root, args, config, store):
    tile = min(args.tile or config.get("tile_size", 4096), args.resolution)
    cmd = [cli, "-q", "build", os.path.join(root, scene["file"]), "-o", store, "--overwrite", "--json",
           "-r", str(args.resolution), "--tile", str(tile), "-j", str(config.get("build_threads", 2)),
           "-m", args.methods, "--up", scene.get("up", "z"),
           "--sun", ",".join(str(x) for x in scene.get("sun", [135, 45])), "--receivers", args.receivers]
    for mesh in scene.get("heightfield", []):
        cmd += ["--heightfield", mesh]
    return cmd + extra


def run_build(cmd):
    """The build's JSON statistics, its process CPU seconds and wall seconds."""
    start = time.monotonic()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        process = subprocess.Popen(cmd, stdout=out, stderr=err)
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        wall = time.monotonic() - start
        out.seek(0)
        err.seek(0)
        if process.returncode != 0:
            sys.exit(f"build failed ({process.returncode}): {' '.join(cmd)}\n{err.read().decode(errors='replace')}")
        stats = json.loads(out.read())
    stats = stats.get("stats", stats)
    return {"stats": stats, "cpu_s": usage.ru_utime + usage.ru_stime, "wall_s": wall}


def wall_over_rays(run):
    seconds = run["stats"]["seconds"]
    return seconds["total"] / seconds["ray_casting_wall"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--a", required=True, help="the shadowtiles executable A (the change)")
    ap.add_argument("--b", default="", help="the shadowtiles executable B (the baseline; default: A)")
    ap.add_argument("--a-args", default="", help="extra build options for A (one string, split as a shell does)")
    ap.add_argument("--b-args", default="", help="extra build options for B")
    ap.add_argument("--config", default="config/bench-standard.json", help="bench config (scenes, sun, threads)")
    ap.add_argument("--scenes", required=True, help="scene names of the config, comma-separated")
    ap.add_argument("--resolution", type=int, default=16384, help="map side in texels")
    ap.add_argument("--receivers", default="surfaces", help="receiver contract")
    ap.add_argument("--methods", default="mh,mmh,dagmh", help="methods to build")
    ap.add_argument("--tile", type=int, default=2048, help="tile side (0: the config's)")
    ap.add_argument("--runs", type=int, default=5, help="builds of each side per scene")
    ap.add_argument("--work", default="", help="scratch directory for the stores (default: a temporary one)")
    ap.add_argument("--json", default="", help="also write every run's figures here")
    args = ap.parse_args()
    if args.runs < 1:
        sys.exit("--runs must be at least 1")

    with open(args.config) as f:
        config = json.load(f)
    root = os.path.join(os.path.dirname(os.path.abspath(args.config)), config["scene_root"])
    by_name = {s["name"]: s for s in config["scenes"]}
    names = [s for s in args.scenes.split(",") if s]
    for name in names:
        if name not in by_name:
            sys.exit(f"no scene {name!r} in {args.config} (it has {', '.join(by_name)})")
    sides = {"A": (args.a, shlex.split(args.a_args)), "B": (args.b or args.a, shlex.split(args.b_args))}
    work = args.work or tempfile.mkdtemp(prefix="build-ab-")
    report = {"a": args.a, "b": args.b or args.a, "a_args": args.a_args, "b_args": args.b_args,
              "resolution": args.resolution, "receivers": args.receivers, "methods": args.methods,
              "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "scenes": []}
    print(f"A = {args.a} {args.a_args}".rstrip())
    print(f"B = {args.b or args.a} {args.b_args}".rstrip())
    print(f"{args.resolution}^2, {args.receivers}, {args.methods}, {args.runs} alternated pairs per scene\n")
    try:
        for name in names:
            scene = by_name[name]
            runs = {"A": [], "B": []}
            same, difference = None, []
            for r in range(args.runs):
                stores = {}
                for side in ("A", "B"):
                    cli, extra = sides[side]
                    stores[side] = os.path.join(work, f"{name}-{side}.store")
                    shutil.rmtree(stores[side], ignore_errors=True)  # a leftover store would be resumed
                    runs[side].append(run_build(build_command(cli, extra, scene, root, args, config, stores[side])))
                if r == 0:  # the first pair's stores: the same build?
                    diff = subprocess.run([args.a, "-q", "store-diff", stores["A"], stores["B"]], capture_output=True,
                                          text=True)
                    if diff.returncode not in (0, 3):
                        sys.exit(f"store-diff failed ({diff.returncode}):\n{diff.stdout}{diff.stderr}")
                    same = diff.returncode == 0
                    difference = (diff.stdout + diff.stderr).strip().splitlines()[:1]
                for store in stores.values():
                    shutil.rmtree(store, ignore_errors=True)
            cpu = [a["cpu_s"] / b["cpu_s"] for a, b in zip(runs["A"], runs["B"])]
            ratio = [wall_over_rays(a) / wall_over_rays(b) for a, b in zip(runs["A"], runs["B"])]
            print(f"## {name}: stores {'the same build' if same else 'DIFFER'}")
            if not same:  # where (store-diff's first difference), and what each side stores
                print(f"store-diff: {difference[0] if difference else '(no message)'}")
                for side in ("A", "B"):
                    stored = runs[side][0]["stats"].get("bytes_by_method", {})
                    print(f"{side} stores " + ", ".join(f"{m} {b:,} B" for m, b in sorted(stored.items())))
            print(f"A/B process CPU per pair: {', '.join(f'{x:.3f}' for x in cpu)}; median {statistics.median(cpu):.3f}")
            print(f"A/B wall/rays per pair: {', '.join(f'{x:.3f}' for x in ratio)}; median {statistics.median(ratio):.3f}")
            print("| | A median | B median | A / rays | B / rays |")
            print("|---|---|---|---|---|")
            rows = [("wall/rays", wall_over_rays), ("process CPU s", lambda run: run["cpu_s"]),
                    ("total s", lambda run: run["stats"]["seconds"]["total"])]
            for label, value in rows:
                a, b = (statistics.median(value(run) for run in runs[side]) for side in ("A", "B"))
                print(f"| {label} | {a:.3f} | {b:.3f} | | |")
            for phase in PHASES:
                medians, shares = [], []
                for side in ("A", "B"):  # a binary older than a phase's timer has none: "-", not 0
                    timed = [run["stats"]["seconds"] for run in runs[side] if phase in run["stats"]["seconds"]]
                    share = [t[phase] / t["rays_thread_sum"] for t in timed if t["rays_thread_sum"] > 0]
                    medians.append(f"{statistics.median(t[phase] for t in timed):.3f}" if timed else "-")
                    shares.append(f"{statistics.median(share):.3f}" if share else "-")
                print(f"| {phase} | " + " | ".join(medians + shares) + " |")
            print()
            report["scenes"].append({"scene": name, "same_build": same, "first_difference": difference,
                                     "cpu_a_over_b": cpu, "wall_over_rays_a_over_b": ratio, "runs": runs})
            if args.json:  # after every scene, so a later failure keeps what was measured
                with open(args.json, "w") as f:
                    json.dump(report, f, indent=1)
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
