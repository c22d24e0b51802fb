#!/usr/bin/env python3
"""Where a build's wall time goes, per scene and contract, from a bench/build_sizes.py run
(docs/build-time.md). Every phase is a thread sum divided by the worker threads, so the columns add
up to the render wall less `idle` (workers waiting: the last tiles, allocation, bookkeeping).

    python3 bench/build_sizes.py --config config/bench-standard.json --resolution 16384 \\
        --methods mh,mmh,dagmh --receivers anywhere,surfaces --out out/build-time-16k.json
    python3 bench/build_phases.py out/build-time-16k.json [--before out/build-time-16k-before.json]

With --before (a run of another binary, interleaved with this one in the same locked session), a
before column gives that run's wall/rays for the same scene and contract.
"""
import argparse
import json


def load(path):
    with open(path) as f:
        doc = json.load(f)
    return doc, {(e["scene"], e.get("receivers", "anywhere")): e for e in doc["scenes"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run")
    ap.add_argument("--before", default="")
    args = ap.parse_args()
    doc, entries = load(args.run)
    before = load(args.before)[1] if args.before else {}
    head = ["scene", "contract", "tiles"] + (["before wall/rays"] if before else []) + [
        "wall/rays", "wall s", "rays", "caps", "entry rule", "MH (build, encode, zstd)", "MMH (merge, encode, zstd)",
        "DAG-MH (encode, zstd)", "previews", "LMDB writes", "idle"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for key, e in entries.items():
        s = e["stats"]
        t = s["threads"]
        sec, em = s["seconds"], s["encode_seconds_by_method"]
        rays = (sec["bvh_thread_sum"] + sec["rays_thread_sum"]) / t
        parts = [sec["caps_thread_sum"], sec.get("entry_rule_thread_sum", 0), em.get("mh", 0), em.get("mmh", 0), em.get("dagmh", 0),
                 sec["preview_thread_sum"], sec["store_thread_sum"]]
        idle = sec["render_wall"] - rays - sum(parts) / t
        row = [e["scene"], key[1], str(s["tiles"]["with_triangles"])]
        if before:
            b = before.get(key)
            row.append(f"{b['stats']['wall_over_ray_casting']:.2f}" if b else "-")
        row += [f"{s['wall_over_ray_casting']:.2f}", f"{sec['total']:.1f}", f"{rays:.1f}"]
        row += [f"{p / t:.1f}" for p in parts] + [f"{idle:.1f}"]
        print("| " + " | ".join(row) + " |")
    print(f"\nRun {args.run}: commit {doc.get('git_commit')}, {doc.get('date')}, methods {','.join(doc['methods'])}, "
          f"{doc['resolution']}^2" + (f" in {doc['tile']}^2 tiles" if "tile" in doc else "") + "; seconds per worker thread.")


if __name__ == "__main__":
    main()
