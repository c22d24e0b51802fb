#!/usr/bin/env python3
"""Turn `shadowtiles bench` results.json files into BENCHMARKS.md and charts (SVG + PNG).

    python3 bench/make_report.py OUT/results.json [MORE/results.json ...] [--md BENCHMARKS.md] [--charts docs/bench]

Several results files (e.g. the standard run and a separate 64K run) are reported as one: their rows
are concatenated (a later file's row replaces an earlier one for the same scene, resolution and method)
and every run's machine, date and commit is listed.

Charts use matplotlib (Debian python3-matplotlib): one library for both SVG and PNG, and the script
already needs Python for the JSON and the tables. If the `python3` on PATH lacks matplotlib (e.g. a
pyenv interpreter), the script re-runs itself with Debian's /usr/bin/python3.
"""
import argparse
import re
import json
import math
import os
import sys

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
except ImportError:  # pragma: no cover - depends on the interpreter
    if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and os.path.exists("/usr/bin/python3"):
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    sys.exit("make_report.py needs matplotlib: apt-get install python3-matplotlib")

# The papers' figures (docs/architecture.md §6, §7): their scenes, not ours; printed as anchors only.
PAPER_SBE16B = {  # SBE16b Table 1, MB
    "Closed City": {"mh": {4096: 0.41, 16384: 2.10, 65536: 9.33, 262144: 38.43},
                    "mmh": {4096: 0.30, 16384: 1.43, 65536: 5.80, 262144: 23.73}},
    "Villa": {"mh": {4096: 0.88, 16384: 5.01, 65536: 23.61, 262144: 101.52},
              "mmh": {4096: 0.63, 16384: 3.62, 65536: 17.36, 262144: 74.11}},
}
PAPER_SE21 = {  # SE21 Table 1, MB
    "Citadel": {"dag": {16384: 3.88, 65536: 17.0, 262144: 69.6}, "mmh": {16384: 1.58, 65536: 6.52, 262144: 26.93},
                "dagmh": {16384: 1.21, 65536: 4.68, 262144: 16.59}},
    "Hairball": {"dag": {16384: 71.5, 65536: 262.5, 262144: 1086.6}, "mmh": {16384: 27.3, 65536: 122.5},
                 "dagmh": {16384: 18.0, 65536: 67.3, 262144: 239.9}},
}
METHOD_ORDER = ["raw", "mh", "mmh", "dagmh", "cpvs", "sst"]
MARKERS = {"raw": "o", "mh": "s", "mmh": "D", "dagmh": "^", "cpvs": "v", "sst": "P"}


def res_label(r):
    r = int(r)
    return f"{r // 1024}K" if r >= 1024 and r % 1024 == 0 else str(r)


def mb(b):
    return b / 1e6


def fmt_bytes(b):
    if b >= 1e9:
        return f"{b / 1e9:.2f} GB"
    if b >= 1e6:
        return f"{b / 1e6:.2f} MB"
    if b >= 1e3:
        return f"{b / 1e3:.1f} kB"
    return f"{b:.0f} B"


def mrate(x):
    return f"{x / 1e6:.2f}" if x else "-"


def scenes_of(rows):
    seen = []
    for r in rows:
        if r["scene"] not in seen:
            seen.append(r["scene"])
    return seen


def methods_of(rows):
    present = {r["method"] for r in rows}
    return [m for m in METHOD_ORDER if m in present] + sorted(present - set(METHOD_ORDER))


def series(rows, scene, method):
    return sorted((r for r in rows if r["scene"] == scene and r["method"] == method), key=lambda r: r["resolution"])


def grid(n):
    cols = min(n, 3)
    return math.ceil(n / cols), cols


def save(fig, charts_dir, name):
    paths = []
    for ext in ("svg", "png"):
        path = os.path.join(charts_dir, f"{name}.{ext}")
        fig.savefig(path, dpi=110 if ext == "png" else None, bbox_inches="tight")
        paths.append(path)
    plt.close(fig)
    return paths


def per_scene_chart(rows, charts_dir, name, title, draw):
    scenes = scenes_of(rows)
    nr, nc = grid(len(scenes))
    fig, axes = plt.subplots(nr, nc, figsize=(4.2 * nc, 3.3 * nr), squeeze=False)
    for i, scene in enumerate(scenes):
        ax = axes[i // nc][i % nc]
        draw(ax, scene)
        ax.set_title(scene, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.tick_params(labelsize=8)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())  # log axes: no crowded minor labels
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    for j in range(len(scenes), nr * nc):
        axes[j // nc][j % nc].axis("off")
    handles, labels = axes[0][0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 7), fontsize=8,
                   bbox_to_anchor=(0.5, -0.02))
    fig.suptitle(title, fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return save(fig, charts_dir, name)


def make_charts(rows, builds, charts_dir):
    os.makedirs(charts_dir, exist_ok=True)
    methods = methods_of(rows)

    def error_vs_bytes(ax, scene):
        for m in methods:
            s = series(rows, scene, m)
            if not s:
                continue
            x = [mb(r["blob_bytes"]) for r in s]
            y = [100 * r["error_rate"] for r in s]
            ax.plot(x, y, marker=MARKERS.get(m, "x"), label=m)
            for r, xi, yi in zip(s, x, y):
                ax.annotate(res_label(r["resolution"]), (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_xlabel("MB at rest", fontsize=8)
        ax.set_ylabel("receivers wrong (%)", fontsize=8)

    def error_vs_speed(ax, scene):
        for m in methods:
            s = series(rows, scene, m)
            if not s:
                continue
            x = [r.get("lps_point_rows_t1", 0) / 1e6 for r in s]
            y = [100 * r["error_rate"] for r in s]
            ax.plot(x, y, marker=MARKERS.get(m, "x"), linestyle=":", label=m)
            for r, xi, yi in zip(s, x, y):
                ax.annotate(res_label(r["resolution"]), (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points")
        # The peer: Embree occlusion rays toward the sun (the ground truth itself: error 0).
        e = [r for r in rows if r["scene"] == scene and r.get("embree_lps_point_rows_t1")]
        seen = set()
        for r in e:
            if r["resolution"] in seen:
                continue
            seen.add(r["resolution"])
            ax.plot([r["embree_lps_point_rows_t1"] / 1e6], [0], marker="*", color="black", linestyle="",
                    label="Embree ray" if len(seen) == 1 else None)
        ax.set_xscale("log")
        ax.set_xlabel("point lookups/s (M, 1 thread, row order)", fontsize=8)
        ax.set_ylabel("receivers wrong (%)", fontsize=8)

    def bytes_vs_res(ax, scene):
        ref = series(rows, scene, methods[0])
        for m in methods:
            s = series(rows, scene, m)
            if s:
                ax.plot([r["resolution"] for r in s], [mb(r["blob_bytes"]) for r in s], marker=MARKERS.get(m, "x"), label=m)
        if ref:
            ax.plot([r["resolution"] for r in ref], [mb(r["float32_bytes"]) for r in ref], "k--", label="float32 map")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("map side (texels)", fontsize=8)
        ax.set_ylabel("MB", fontsize=8)

    charts = {
        "error_vs_bytes": per_scene_chart(rows, charts_dir, "error_vs_bytes",
                                          "Point-query error vs bytes at rest (labels: resolution)", error_vs_bytes),
        "error_vs_speed": per_scene_chart(rows, charts_dir, "error_vs_speed",
                                          "Point-query error vs lookups/s (labels: resolution)", error_vs_speed),
        "bytes_vs_resolution": per_scene_chart(rows, charts_dir, "bytes_vs_resolution",
                                               "Bytes at rest vs resolution (dashed: uncompressed float32 map)",
                                               bytes_vs_res),
    }
    def encode_vs_res(ax, scene):
        for m in methods:
            s = [r for r in series(rows, scene, m) if r.get("build_method_encode_s")]
            if s:
                ax.plot([r["resolution"] for r in s], [r["build_method_encode_s"] for r in s],
                        marker=MARKERS.get(m, "x"), label=m)
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("map side (texels)", fontsize=8)
        ax.set_ylabel("encode seconds (thread sum)", fontsize=8)

    charts["encode_seconds"] = per_scene_chart(
        rows, charts_dir, "encode_seconds",
        "Encode seconds per method vs resolution (MH construction counted under mh; rays shared by all)", encode_vs_res)
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for scene in scenes_of(rows):
        b = sorted((x for x in builds if x["scene"] == scene), key=lambda x: x["resolution"])
        ax.plot([x["resolution"] for x in b], [x["stats"]["seconds"]["total"] for x in b], marker="o", label=scene)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("map side (texels)")
    ax.set_ylabel("build wall seconds (all methods)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Build time vs resolution", fontsize=11)
    fig.tight_layout()
    charts["build_seconds"] = save(fig, charts_dir, "build_seconds")
    return charts


def table(header, lines):
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in line) + " |" for line in lines]
    return "\n".join(out)


def anchors(rows, sizes=()):
    parts = ["Printed beside ours for scale only: **these are the papers' figures on the papers' scenes** "
             "(Closed City, Villa, Citadel, Hairball), which are not ours. Compare ratios, not bytes."]
    lines = []
    for scene, d in PAPER_SBE16B.items():
        for r in sorted(d["mh"]):
            lines.append([f"paper SBE16b: {scene}", res_label(r), f"{d['mh'][r]:.2f}", f"{d['mmh'][r]:.2f}",
                          f"{d['mmh'][r] / d['mh'][r]:.2f}"])
    for scene in scenes_of(rows):
        mh = {r["resolution"]: r["blob_bytes"] for r in series(rows, scene, "mh")}
        mmh = {r["resolution"]: r["blob_bytes"] for r in series(rows, scene, "mmh")}
        for r in sorted(mh):
            lines.append([f"ours: {scene}", res_label(r), f"{mb(mh[r]):.2f}",
                          f"{mb(mmh[r]):.2f}" if r in mmh else "-", f"{mmh[r] / mh[r]:.2f}" if r in mmh else "-"])
    parts.append("**MMH vs MH** (MB; docs/architecture.md §6)\n\n" + table(["source", "res", "MH MB", "MMH MB", "MMH/MH"], lines))
    lines = []
    for scene, d in PAPER_SE21.items():
        for r in sorted(d["dagmh"]):
            m = d["mmh"].get(r)
            lines.append([f"paper SE21: {scene}", res_label(r), f"{d['dag'][r]:.2f}", f"{m:.2f}" if m else "-",
                          f"{d['dagmh'][r]:.2f}", f"{d['dagmh'][r] / m:.2f}" if m else "-"])
    for scene in scenes_of(rows):
        mmh = {r["resolution"]: r["blob_bytes"] for r in series(rows, scene, "mmh")}
        dag = {r["resolution"]: r["blob_bytes"] for r in series(rows, scene, "dagmh")}
        for r in sorted(dag):
            lines.append([f"ours: {scene}", res_label(r), "-", f"{mb(mmh[r]):.2f}" if r in mmh else "-",
                          f"{mb(dag[r]):.2f}", f"{dag[r] / mmh[r]:.2f}" if r in mmh else "-"])
    for e in sizes:
        b = e["stats"].get("bytes_by_method", {})
        if "dagmh" in b and "mmh" in b:
            lines.append([f"ours (sizes run): {e['scene']}", res_label(e["resolution"]), "-", f"{mb(b['mmh']):.2f}",
                          f"{mb(b['dagmh']):.2f}", f"{b['dagmh'] / b['mmh']:.2f}"])
    if not any(r["method"] == "dagmh" for r in rows):
        lines.append(["ours", "-", "-", "-", "not built yet", "-"])
    parts.append("**DAG-MH vs MMH** (MB; docs/architecture.md §7)\n\n" +
                 table(["source", "res", "DAG MB", "MMH MB", "DAG-MH MB", "DAG-MH/MMH"], lines))
    return "\n\n".join(parts)


def sizes_section(sizes):
    """Builds without ground truth or lookups (bench/build_sizes.py): bytes and encode time per method."""
    methods = [m for m in METHOD_ORDER if any(m in e["stats"].get("bytes_by_method", {}) for e in sizes)]
    out = ["## Sizes-only runs", "",
           "Built by `bench/build_sizes.py` (same scenes, sun and tiles as the bench; no ground truth or lookups: at "
           "64K² the bench's raw reference would need 34 GB decoded). Bytes at rest (tiles + top levels), encode "
           "seconds as thread sums (MH construction counted under mh).", ""]
    lines = []
    for e in sorted(sizes, key=lambda e: (e["resolution"], e["scene"])):
        st = e["stats"]
        b, t = st.get("bytes_by_method", {}), st.get("encode_seconds_by_method", {})
        top, p = st.get("top_bytes_by_method", {}), st.get("payload_bytes_by_method", {})
        lines.append([e["scene"], res_label(e["resolution"])] +
                     [fmt_bytes(b[m] + top.get(m, 0)) if m in b else "-" for m in methods] +
                     [f"{b['dagmh'] / b['mmh']:.3f}" if "dagmh" in b and "mmh" in b else "-"] +
                     [f"{p['dagmh'] / p['mmh']:.3f}" if "dagmh" in p and "mmh" in p else "-"] +
                     [f"{t[m]:.0f}" if m in t else "-" for m in methods] +
                     [f"{st.get('seconds', {}).get('rays_thread_sum', 0):.0f}", f"{e.get('wall_s', 0):.0f}",
                      f"{st.get('peak_memory_mib', 0):.0f}"])
    out.append(table(["scene", "res"] + [f"{m} bytes" for m in methods] + ["DAG-MH/MMH", "DAG-MH/MMH payload"] +
                     [f"{m} encode s" for m in methods] + ["rays Σ s", "wall s", "peak MiB"], lines))
    return out + [""]


def report(doc, charts, md_path, sizes=()):
    rows, builds = doc["rows"], doc["builds"]
    rel = lambda p: os.path.relpath(p, os.path.dirname(os.path.abspath(md_path)))
    out = ["# Benchmarks", "",
           "Generated by `bench/make_report.py` from `shadowtiles bench` results; do not edit by hand. Regenerate:", "",
           "```sh",
           "bash bench/run_full.sh   # bench 4K+16K (config/bench-standard.json), sizes-only 64K, then this report",
           "# quick: shadowtiles bench --config config/bench-quick.json --out out/bench-quick; make_report.py out/bench-quick/results.json",
           "```", "",
           ]
    for run in doc["runs"]:
        machine, cfg = run["machine"], run.get("config", {})
        where = (f"{machine.get('cpu_model')} ({machine.get('nproc')} threads), {machine.get('memory_gib', 0):.0f} GiB; "
                 if machine.get("cpu_model") else "same machine; ")
        out += [f"Run `{run['file']}`: {where}date {machine.get('date')}; commit `{machine.get('git_commit')}`"
                f"{' (dirty tree)' if machine.get('git_dirty') else ''}. Config: {cfg.get('description', '')}", ""]
    for note in doc.get("notes", []):
        out.append(f"- Note: {note}")
    out += ["", "## How to read", "",
            "- **bytes**: tile blobs at rest (32-byte header + zstd payload), summed over the `tiles` database; "
            "**payload**: decoded bytes; **B/texel**: bytes at rest per non-empty texel (raw lower bound < 1); "
            "**ratio**: float32 map (4 R² bytes) / bytes at rest.",
            "- **build**: one build per scene and resolution encodes every method, so sizes compare within one run; "
            "phases are per build (thread sums for BVH, rays, encode, store); peak RSS is the bench process's during the build "
            "(it also holds the scene and the ground-truth BVH).",
            "- **error**: receivers sampled uniformly by area on the scene's surfaces (and, `cam`, the visible pixels of a "
            "fixed camera) whose lit/shadowed answer at the build's default bias (2 texels) disagrees with an Embree "
            "occlusion ray toward the sun (same epsilon for every method); **f-lit** = light leaks, **f-shad** = acne or lost detail.",
            "- **PCF MAE**: mean |store's k×k lit fraction − ground truth| on the uniform receivers; the truth traces 2×2 "
            "jittered samples per kernel texel, the kernel's light-space footprint projected along the light onto the "
            "receiver's tangent plane (so it is the true visibility of the surface around the receiver; PCF's own "
            "slope acne and the resolution count as error).",
            "- **lookups/s**: ShadowMap::query / query_pcf through the client API (cache lock included) after a warm-up "
            "pass, ≥ min_seconds per loop; rows = receivers sorted along light-space rows, cam = camera pixels in screen "
            "order, rand = shuffled; ×2 = two threads.", ""]
    out += ["## Charts", ""]
    for name, title in [("error_vs_bytes", "Error vs bytes"), ("error_vs_speed", "Error vs lookups/s"),
                        ("bytes_vs_resolution", "Bytes vs resolution"), ("build_seconds", "Build seconds vs resolution"),
                        ("encode_seconds", "Encode seconds per method vs resolution")]:
        svg = [p for p in charts[name] if p.endswith(".svg")][0]
        png = [p for p in charts[name] if p.endswith(".png")][0]
        out += [f"**{title}** ([SVG]({rel(svg)}))", "", f"![{title}]({rel(png)})", ""]
    for scene in scenes_of(rows):
        srows = sorted((r for r in rows if r["scene"] == scene),
                       key=lambda r: (r["resolution"], METHOD_ORDER.index(r["method"]) if r["method"] in METHOD_ORDER else 99))
        out += [f"## {scene}", ""]
        out.append(table(["res", "method", "bytes", "payload", "B/texel", "ratio", "err %", "f-lit", "f-shad", "cam err %",
                          "≠raw", "pcf3 MAE", "pcf5 MAE", "encode s"],
                         [[res_label(r["resolution"]), r["method"], fmt_bytes(r["blob_bytes"]), fmt_bytes(r["payload_bytes"]),
                           f"{r['bytes_per_nonempty_texel']:.3f}", f"{r['compression_ratio']:.1f}",
                           f"{100 * r['error_rate']:.3f}", r["false_lit"], r["false_shadowed"],
                           f"{100 * r['camera_error_rate']:.3f}", r["differs_from_raw"],
                           f"{r.get('pcf3_mae', 0):.4f}", f"{r.get('pcf5_mae', 0):.4f}",
                           f"{r['build_method_encode_s']:.1f}" if "build_method_encode_s" in r else "-"] for r in srows]))
        out += ["", "Lookups/s (millions):", ""]
        out.append(table(["res", "method", "point rows", "point cam", "point rand", "point rows ×2", "point rand ×2",
                          "pcf3 rows", "pcf3 rand", "pcf5 rows", "pcf5 rand", "pcf5 rand ×2"],
                         [[res_label(r["resolution"]), r["method"], mrate(r.get("lps_point_rows_t1")),
                           mrate(r.get("lps_point_camera_t1")), mrate(r.get("lps_point_random_t1")),
                           mrate(r.get("lps_point_rows_t2")), mrate(r.get("lps_point_random_t2")),
                           mrate(r.get("lps_pcf3_rows_t1")), mrate(r.get("lps_pcf3_random_t1")),
                           mrate(r.get("lps_pcf5_rows_t1")), mrate(r.get("lps_pcf5_random_t1")),
                           mrate(r.get("lps_pcf5_random_t2"))] for r in srows]))
        if any(r.get("embree_lps_point_rows_t1") for r in srows):
            def x(v, d=2):
                return f"{v:.{d}f}" if v else "-"
            out += ["", "Against Embree occlusion rays (one `rtcOccluded1` toward the sun per receiver, same receivers, "
                    "orders and threads; ×2 = 2 threads), batch = `query_batch` of the shuffled batch points (Embree: "
                    "the same points in the batch's sort order), cold = first batch on a freshly opened store:", ""]
            out.append(table(["res", "method", "Embree rows ×2", "rows ×2 / Embree", "rand ×2 / Embree", "batch ×2",
                              "batch / Embree", "2t/1t rows", "2t/1t rand", "pcf3/point cost", "p50 µs", "p99 µs",
                              "cold s", "cold read", "decoded/payload", "cache peak", "RSS MiB"],
                             [[res_label(r["resolution"]), r["method"], mrate(r.get("embree_lps_point_rows_t2")),
                               x(r.get("vs_embree_point_rows_t2")), x(r.get("vs_embree_point_random_t2")),
                               mrate(r.get("lps_batch_t2")), x(r.get("vs_embree_batch_t2")),
                               x(r.get("lps_point_rows_t2", 0) / r["lps_point_rows_t1"] if r.get("lps_point_rows_t1") else 0),
                               x(r.get("lps_point_random_t2", 0) / r["lps_point_random_t1"] if r.get("lps_point_random_t1") else 0),
                               x(r.get("pcf3_over_point_cost")), x(r.get("point_latency_p50_us")),
                               x(r.get("point_latency_p99_us")), x(r.get("cold_batch_s"), 3),
                               fmt_bytes(r.get("cold_batch_bytes_read", 0)), x(r.get("decoded_over_payload")),
                               fmt_bytes(r.get("cache_peak_bytes", 0)), x(r.get("lookup_rss_mib"), 0)] for r in srows]))
        out += ["", "Build (all methods in one build), seconds:", ""]
        b = sorted((x for x in builds if x["scene"] == scene), key=lambda x: x["resolution"])
        out.append(table(["res", "load", "index", "BVH Σ", "rays Σ", "encode Σ", "store Σ", "wall", "rays", "peak RSS MiB"],
                         [[res_label(x["resolution"])] + [f"{x['stats']['seconds'].get(k, 0):.2f}" for k in
                          ("load", "index", "bvh_thread_sum", "rays_thread_sum", "encode_thread_sum", "store_thread_sum", "total")]
                          + [x["stats"].get("rays", 0), f"{x.get('peak_rss_mib', 0):.0f}"] for x in b]))
        out.append("")
    if sizes:
        out += sizes_section(sizes)
    out += ["## Paper anchors", "", anchors(rows, sizes), ""]
    out += ["## Summary: bytes, error and lookups/s per method", ""]
    lines = []
    for r in sorted(rows, key=lambda r: (r["resolution"], r["scene"], r["method"])):
        lines.append([r["scene"], res_label(r["resolution"]), r["method"], fmt_bytes(r["blob_bytes"]),
                      f"{100 * r['error_rate']:.3f}", mrate(r.get("lps_point_rows_t1")), mrate(r.get("lps_pcf5_rows_t1"))])
    out.append(table(["scene", "res", "method", "bytes", "err %", "point M/s", "pcf5 M/s"], lines))
    out.append("")
    # The query section (bench/query_report.py) and the two-contract size table (bench/contract_sizes.py)
    # come from other runs: keep them.
    if os.path.exists(md_path):
        with open(md_path) as f:
            previous = f.read()
        for name in ("queries", "queries-surfaces", "contract-sizes"):
            kept = re.search(f"<!-- {name}:begin -->.*?<!-- {name}:end -->", previous, re.S)
            if kept:
                out += [kept.group(0), ""]
    with open(md_path, "w") as f:
        f.write("\n".join(out))


def merge_runs(paths):
    """One document from several runs: rows and builds keyed by (scene, resolution[, method]), later wins."""
    rows, builds, runs, notes = {}, {}, [], []
    for path in paths:
        with open(path) as f:
            doc = json.load(f)
        if not doc.get("rows"):
            sys.exit("no rows in " + path)
        runs.append({"file": path, "machine": doc.get("machine", {}), "config": doc.get("config", {})})
        notes += doc.get("notes", [])
        for r in doc["rows"]:
            rows[(r["scene"], r["resolution"], r["method"])] = r
        for b in doc.get("builds", []):
            builds[(b["scene"], b["resolution"])] = b
    return {"rows": list(rows.values()), "builds": list(builds.values()), "runs": runs,
            "notes": sorted(set(notes), key=notes.index)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", nargs="+", help="results.json files written by `shadowtiles bench`")
    ap.add_argument("--sizes", nargs="*", default=[], help="sizes-only runs written by bench/build_sizes.py")
    ap.add_argument("--note", action="append", default=[], help="a note to print under the runs (repeatable)")
    ap.add_argument("--md", default="BENCHMARKS.md", help="Markdown report to write")
    ap.add_argument("--charts", default="docs/bench", help="folder for the SVG and PNG charts")
    args = ap.parse_args()
    doc = merge_runs(args.results)
    sizes = []
    for path in args.sizes:
        with open(path) as f:
            run = json.load(f)
        sizes += run["scenes"]
        doc["runs"].append({"file": path, "machine": {"date": run.get("date"), "git_commit": run.get("git_commit"),
                                                      "git_dirty": run.get("git_dirty")},
                            "config": {"description": f"sizes-only builds at {run.get('resolution')}^2 of "
                                                      f"{', '.join(run.get('methods', []))} (bench/build_sizes.py)"}})
    doc["notes"] += args.note
    charts = make_charts(doc["rows"], doc.get("builds", []), args.charts)
    report(doc, charts, args.md, sizes)
    print(f"wrote {args.md} and {len(charts)} charts (SVG + PNG) in {args.charts}")


if __name__ == "__main__":
    main()
