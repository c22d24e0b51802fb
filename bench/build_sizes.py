#!/usr/bin/env python3
"""Sizes-only runs: build every scene of a bench config at one resolution and record what each
method stores, without the bench's ground truth and lookup loops (which need the raw reference
decoded in memory: 34 GB at 64K^2, more than the machine has).

    python3 bench/build_sizes.py --config config/bench-standard.json --resolution 65536 \
        --methods mh,mmh,dagmh --out out/sizes-64k.json [--scenes a,b] [--cli build/cli/shadowtiles]
        [--receivers anywhere,surfaces] [--accuracy 20000]

With --receivers, every scene is built once per receiver contract (docs/receiver-contracts.md) and
each entry records its contract; bench/contract_sizes.py turns such a run into the two-contract table.
With --accuracy N, each store is kept until `shadowtiles accuracy` has counted every method's false-lit
and false-shadowed answers on N surface receivers against Embree ground truth (the bench's evaluator,
tile by tile through ShadowMap, so no whole map is decoded); the counts go into the entry.

One `shadowtiles build --json` per scene (same sun, up axis and heightfield flags as the bench),
the store deleted afterwards. The output is rewritten after every scene and scenes already in it
are skipped, so an interrupted run resumes. bench/make_report.py --sizes reads it.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", required=True, help="bench config (scenes, sun, tile size, threads)")
    ap.add_argument("--resolution", type=int, required=True, help="map side in texels (power of two)")
    ap.add_argument("--methods", default="mh,mmh,dagmh", help="methods to build, comma-separated")
    ap.add_argument("--out", required=True, help="JSON file to write (and resume from)")
    ap.add_argument("--scenes", default="", help="only these scenes (comma-separated names)")
    ap.add_argument("--cli", default="build/cli/shadowtiles", help="the shadowtiles executable")
    ap.add_argument("--receivers", default="anywhere", help="receiver contracts to build, comma-separated")
    ap.add_argument("--work", default="out/build-sizes-store", help="scratch store directory")
    ap.add_argument("--tile", type=int, default=0, help="tile side (default: the config's tile_size)")
    ap.add_argument("--accuracy", type=int, default=0, help="surface receivers for the error counts (0: none)")
    args = ap.parse_args()

    with open(args.config) as f:
        config = json.load(f)
    root = os.path.join(os.path.dirname(os.path.abspath(args.config)), config["scene_root"])
    wanted = [s for s in args.scenes.split(",") if s]
    commit = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                           text=True).stdout.strip() != ""
    doc = {"resolution": args.resolution, "methods": args.methods.split(","), "config": args.config,
           "tile": min(args.tile or config.get("tile_size", 4096), args.resolution),
           "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "git_commit": commit, "git_dirty": dirty,
           "scenes": []}
    if os.path.exists(args.out):
        with open(args.out) as f:
            doc = json.load(f)
    done = {(s["scene"], s["resolution"], s.get("receivers", "anywhere")) for s in doc["scenes"]}

    for scene, receivers in [(s, r) for s in config["scenes"] for r in args.receivers.split(",")]:
        name = scene["name"]
        if (wanted and name not in wanted) or (name, args.resolution, receivers) in done:
            continue
        cmd = [args.cli, "-q", "build", os.path.join(root, scene["file"]), "-o", args.work, "--overwrite", "--json",
               "-r", str(args.resolution), "--tile", str(min(args.tile or config.get("tile_size", 4096), args.resolution)),
               "-j", str(config.get("build_threads", 2)), "-m", args.methods, "--up", scene.get("up", "z"),
               "--sun", ",".join(str(x) for x in scene.get("sun", [135, 45])),
               "--receivers", receivers]
        for mesh in scene.get("heightfield", []):
            cmd += ["--heightfield", mesh]
        print(f"{name} {args.resolution}^2 {receivers}: {' '.join(cmd)}", flush=True)
        # A store left by a killed run of the same build would be resumed, and a build's byte counts
        # cover only the tiles it rendered itself: always start from an empty store.
        shutil.rmtree(args.work, ignore_errors=True)
        start = time.time()
        result = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.time() - start
        accuracy = None
        if result.returncode == 0 and args.accuracy > 0:
            acc = subprocess.run([args.cli, "-q", "accuracy", args.work, os.path.join(root, scene["file"]),
                                  "--receivers", str(args.accuracy), "--json"], capture_output=True, text=True)
            if acc.returncode != 0:
                shutil.rmtree(args.work, ignore_errors=True)
                sys.exit(f"accuracy of {name} failed ({acc.returncode}):\n{acc.stderr}")
            accuracy = json.loads(acc.stdout)
        shutil.rmtree(args.work, ignore_errors=True)
        if result.returncode != 0:
            sys.exit(f"build of {name} failed ({result.returncode}):\n{result.stderr}")
        stats = json.loads(result.stdout)
        stats = stats.get("stats", stats)
        entry = {"scene": name, "resolution": args.resolution, "receivers": receivers, "wall_s": wall,
                 "stats": stats}
        if accuracy is not None:
            entry["accuracy"] = accuracy
        doc["scenes"].append(entry)
        with open(args.out + ".tmp", "w") as f:
            json.dump(doc, f, indent=1)
        os.replace(args.out + ".tmp", args.out)
        bytes_by = stats.get("bytes_by_method", {})
        print("  " + ", ".join(f"{m} {b:,} B" for m, b in sorted(bytes_by.items())) + f"; {entry['wall_s']:.0f} s",
              flush=True)


if __name__ == "__main__":
    main()
