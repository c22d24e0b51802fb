#!/usr/bin/env python3
"""Write the "Queries" section of BENCHMARKS.md (issue 15) from `shadowtiles bench` results.

    python3 bench/query_report.py out/bench-queries/*/results.json [--md BENCHMARKS.md] [--note TEXT]
                                  [--block queries|queries-surfaces]

bench/run_queries.sh runs the bench (config/bench-queries.json) one scene at a time and then this.
The section lives between the markers below; everything else in the file is left alone (make_report.py,
which writes the rest, keeps the block). Every ratio is of one row, i.e. of one scene's run: 2 threads /
1 thread, store / Embree occlusion rays on the same receivers in the same order with the same threads.
"""
import argparse
import json
import os
import re
import statistics
import sys

# Each block is one config's matrix: `queries` (config/bench-queries.json, build defaults) and
# `queries-surfaces` (config/bench-queries-surfaces.json: the open scenes under the surfaces contract).
BLOCKS = {
    "queries": ("Queries: scaling, Embree, cost, memory (issue 15)", "config/bench-queries.json", ""),
    "queries-surfaces": ("Queries on open scenes under the surfaces contract (issue 15)",
                         "config/bench-queries-surfaces.json",
                         "The open shared scenes built with `--receivers surfaces` (exit caps on): the contract of "
                         "static receivers (lightmaps, solar-access studies), which every receiver here is, since the "
                         "bench samples them on the scene's surfaces. Under `anywhere` (the section above) every "
                         "interval on open geometry has zero width and the trees are full depth."),
}
METHOD_ORDER = ["raw", "mh", "mmh", "dagmh", "cpvs", "sst"]
TREES = ["mh", "mmh", "dagmh"]
# The scaling cells: point and PCF 3x3, row and random order (camera order and batches are shown too).
SCALING_CELLS = [("point", "rows"), ("point", "random"), ("pcf3", "rows"), ("pcf3", "random")]
OPEN_SCANS = {"bunny", "dragon"}  # open scans: deep trees at 16384^2, where MH/MMH must reach raw's rate


def res_label(r):
    r = int(r)
    return f"{r // 1024}K" if r % 1024 == 0 else str(r)


def num(row, key):
    v = row.get(key)
    return v if isinstance(v, (int, float)) else 0.0


def ratio(a, b):
    return a / b if a and b else 0.0


def f2(v, d=2):
    return f"{v:.{d}f}" if v else "-"


def mrate(v):
    return f"{v / 1e6:.2f}" if v else "-"


def fmt_bytes(b):
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if b >= scale:
            return f"{b / scale:.2f} {unit}" if unit != "kB" else f"{b / scale:.1f} kB"
    return f"{b:.0f} B"


def table(header, lines):
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in line) + " |" for line in lines]
    return "\n".join(out)


def scaling(row, kind, order):
    return ratio(num(row, f"lps_{kind}_{order}_t2"), num(row, f"lps_{kind}_{order}_t1"))


def verdict(ok):
    return "**yes**" if ok else "no"


def load(paths):
    rows, runs = {}, []
    for path in paths:
        with open(path) as f:
            doc = json.load(f)
        runs.append((path, doc.get("machine", {})))
        for r in doc.get("rows", []):
            rows[(r["scene"], r["resolution"], r["method"])] = r
    key = lambda r: (r["resolution"], r["scene"], METHOD_ORDER.index(r["method"]) if r["method"] in METHOD_ORDER else 99)
    return sorted(rows.values(), key=key), runs


def targets(rows):
    """The issue's 'What it must show' lines, each with what this run measured."""
    out = []
    cells = [scaling(r, k, o) for r in rows for k, o in SCALING_CELLS if scaling(r, k, o)]
    if cells:
        med, worst = statistics.median(cells), min(cells)
        out.append(["2 threads / 1 thread, every method, point + PCF 3x3, rows + random",
                    "median >= 1.8, every cell >= 1.5", f"median {med:.2f}, worst {worst:.2f} ({len(cells)} cells)",
                    verdict(med >= 1.8 and worst >= 1.5)])
    for res in sorted({r["resolution"] for r in rows}):
        b = [(r, num(r, "vs_embree_batch_t2")) for r in rows if r["resolution"] == res and r["method"] in TREES]
        b = [(r, v) for r, v in b if v]
        if b:
            worst = min(b, key=lambda x: x[1])
            out.append([f"query_batch / Embree, 2 threads, MH/MMH/DAG-MH, {res_label(res)}",
                        ">= 5 in every cell" + (" (the target's resolution)" if res == 16384 else ""),
                        f"worst {worst[1]:.2f} ({worst[0]['scene']} {worst[0]['method']}), "
                        f"{sum(v >= 5 for _, v in b)} of {len(b)} cells >= 5", verdict(worst[1] >= 5)])
    for order, goal in (("rows", 1.5), ("random", 1.0)):
        p = [(r, num(r, f"vs_embree_point_{order}_t2")) for r in rows if num(r, f"vs_embree_point_{order}_t2")]
        if p:
            worst = min(p, key=lambda x: x[1])
            out.append([f"single-point API / Embree, 2 threads, {order}", f">= {goal} in every cell",
                        f"worst {worst[1]:.2f} ({worst[0]['scene']} {res_label(worst[0]['resolution'])} "
                        f"{worst[0]['method']}), {sum(v >= goal for _, v in p)} of {len(p)} cells",
                        verdict(worst[1] >= goal)])
    c = [(r, num(r, "pcf3_over_point_cost")) for r in rows if num(r, "pcf3_over_point_cost")]
    if c:
        worst = max(c, key=lambda x: x[1])
        out.append(["PCF 3x3 cost / point cost (single-point API, rows, 1 thread)", "<= 2.5",
                    f"worst {worst[1]:.2f} ({worst[0]['scene']} {res_label(worst[0]['resolution'])} {worst[0]['method']}), "
                    f"median {statistics.median(v for _, v in c):.2f}", verdict(worst[1] <= 2.5)])
    d = [(r, num(r, "decoded_over_payload")) for r in rows if r["method"] in TREES and num(r, "decoded_over_payload")]
    if d:
        worst = max(d, key=lambda x: x[1])
        out.append(["decoded bytes / payload bytes, MH/MMH/DAG-MH", "<= 1.2",
                    f"worst {worst[1]:.2f} ({worst[0]['scene']} {res_label(worst[0]['resolution'])} {worst[0]['method']})",
                    verdict(worst[1] <= 1.2)])
    h = [(r, num(r, "http_batch_lps_median")) for r in rows if num(r, "http_batch_lps_median")]
    if h:
        worst = min(h, key=lambda x: x[1])
        out.append(["HTTP binary batch of 100k points, loopback, 2 server threads, warm (median of 10 POSTs)",
                    ">= 10 M points/s end to end",
                    f"worst {worst[1] / 1e6:.2f} M/s ({worst[0]['scene']} {res_label(worst[0]['resolution'])} "
                    f"{worst[0]['method']}), median {statistics.median(v for _, v in h) / 1e6:.2f}, "
                    f"{sum(v >= 10e6 for _, v in h)} of {len(h)} cells", verdict(worst[1] >= 10e6)])
    for method in ("mh", "mmh"):
        s = []
        for r in rows:
            if r["method"] != method or r["resolution"] != 16384 or r["scene"] not in OPEN_SCANS:
                continue
            raw = next((x for x in rows if x["method"] == "raw" and x["scene"] == r["scene"] and x["resolution"] == 16384), None)
            for order in ("rows", "random"):
                for t in ("t1", "t2"):
                    v = ratio(num(r, f"lps_point_{order}_{t}"), num(raw, f"lps_point_{order}_{t}") if raw else 0)
                    if v:
                        s.append((r["scene"], order, t, v))
        if s:
            worst = min(s, key=lambda x: x[3])
            out.append([f"{method.upper()} point API / raw, open scans at 16K ({', '.join(sorted(OPEN_SCANS))})",
                        ">= 1 in the same run", f"worst {worst[3]:.2f} ({worst[0]} {worst[1]} {worst[2]})",
                        verdict(worst[3] >= 1)])
    return out


def markers(block):
    return f"<!-- {block}:begin -->", f"<!-- {block}:end -->"


def section(rows, runs, notes, block):
    begin, end = markers(block)
    title, config, intro = BLOCKS[block]
    contracts = sorted({r.get("contract", "anywhere") for r in rows})
    regenerate = "bash bench/run_queries.sh" if block == "queries" else f"CONFIG={config} bash bench/run_queries.sh"
    out = [begin, f"## {title}", ""] + ([intro, ""] if intro else []) + [
           f"Generated by `bench/query_report.py`; regenerate with `{regenerate} "
           f"[scenes]` ({config}: tiles 2048², every method, receiver contract {'/'.join(contracts)}, exit caps on, "
           "20,000 receivers sampled by area, 1M shuffled surface points per batch; rates in interleaved rounds: every "
           "method's lookups, both thread counts, point and PCF, query_batch and Embree's rays each run one round in "
           "turn, 5 rounds of ≥ 0.06 s each (a batch round ≥ 1 batch), and each cell is its best round, so the two "
           "sides of every ratio share the same stretch of wall time and a neighbour's burst on this shared machine "
           "does not set a cell; bench/harness/lookup_rate.hpp). One "
           "`shadowtiles bench` run per scene; every ratio is of one run. Embree = one `rtcOccluded1` toward the sun per "
           "receiver, same receivers, order and threads (batch: the same points in the batch's sort order).", ""]
    for path, m in runs:
        out.append(f"- `{path}`: {m.get('cpu_model', '?')} ({m.get('nproc', '?')} threads), date {m.get('date')}, "
                   f"commit `{m.get('git_commit')}`{' (dirty tree)' if m.get('git_dirty') else ''}")
    out += [f"- Note: {n}" for n in notes]
    out += ["", "### Targets", ""]
    out.append(table(["what", "target", "measured", "met"], targets(rows)))

    out += ["", "### 2 threads / 1 thread (aggregate rate of 2 threads over the rate of 1)", ""]
    lines, per_res = [], {}
    for r in rows:
        cells = [scaling(r, k, o) for k, o in SCALING_CELLS]
        valid = [c for c in cells if c]
        per_res.setdefault(r["resolution"], []).extend(valid)
        lines.append([r["scene"], res_label(r["resolution"]), r["method"]] + [f2(c) for c in cells] +
                     [f2(scaling(r, "point", "camera")), f2(scaling(r, "pcf3", "camera")),
                      f2(ratio(num(r, "lps_batch_t2"), num(r, "lps_batch_t1"))),
                      f2(ratio(num(r, "lps_batch_pcf3_t2"), num(r, "lps_batch_pcf3_t1"))),
                      f2(min(valid)) if valid else "-"])
    out.append(table(["scene", "res", "method", "point rows", "point rand", "pcf3 rows", "pcf3 rand", "point cam",
                      "pcf3 cam", "batch", "batch pcf3", "worst of the 4"], lines))
    out.append("")
    out.append("Median / worst of the four issue cells (point and PCF 3x3, rows and random): " + "; ".join(
        f"{res_label(res)} {statistics.median(c):.2f} / {min(c):.2f} ({len(c)} cells)" for res, c in sorted(per_res.items()) if c) + ".")

    out += ["", "### Against Embree occlusion rays (2 threads; M lookups/s)", ""]
    out.append(table(["scene", "res", "method", "Embree rows", "point rows", "rows / Embree", "Embree rand", "point rand",
                      "rand / Embree", "Embree batch", "query_batch", "batch / Embree", "batch pcf3"],
                     [[r["scene"], res_label(r["resolution"]), r["method"], mrate(num(r, "embree_lps_point_rows_t2")),
                       mrate(num(r, "lps_point_rows_t2")), f2(num(r, "vs_embree_point_rows_t2")),
                       mrate(num(r, "embree_lps_point_random_t2")), mrate(num(r, "lps_point_random_t2")),
                       f2(num(r, "vs_embree_point_random_t2")), mrate(num(r, "embree_lps_batch_t2")),
                       mrate(num(r, "lps_batch_t2")), f2(num(r, "vs_embree_batch_t2")),
                       mrate(num(r, "lps_batch_pcf3_t2"))] for r in rows]))

    out += ["", "### Cost, latency, cold start, memory", "",
            "pcf3/point = point rate / PCF 3x3 rate (rows, 1 thread; batch: query_batch, 1 thread); latency: one "
            "warm single-point query at a time, random order; cold = the first 1M-point batch on a freshly opened "
            "store (2 threads; blob bytes read); HTTP POST = the same batch POSTed (binary) to a `shadowtiles serve` "
            "that has just opened the store, on loopback (seconds to the whole answer; blob bytes the server read); "
            "HTTP 100k = then, warm, binary POSTs of the batch's first 100k points on one keep-alive connection (2 "
            "server threads; M points/s end to end, median of 10 after 2 warm-up); "
            "stream = a streaming client (ShadowMap over HTTP, empty cache) answering it from that server (seconds "
            "including its open; blob bytes fetched over HTTP); decoded = every tile of the method decoded (the cache's bytes); "
            "cache peak and RSS during the lookup runs (the process also holds the scene, the ground-truth BVH and "
            "the other methods' tiles).", ""]
    out.append(table(["scene", "res", "method", "pcf3/point", "batch pcf3/point", "p50 µs", "p99 µs", "cold s",
                      "cold read", "HTTP POST s", "server read", "HTTP 100k M/s", "stream s", "fetched", "payload", "decoded",
                      "decoded/payload", "cache peak", "RSS MiB"],
                     [[r["scene"], res_label(r["resolution"]), r["method"], f2(num(r, "pcf3_over_point_cost")),
                       f2(num(r, "batch_pcf3_over_point_cost")), f2(num(r, "point_latency_p50_us")),
                       f2(num(r, "point_latency_p99_us")), f2(num(r, "cold_batch_s"), 3),
                       fmt_bytes(num(r, "cold_batch_bytes_read")), f2(num(r, "cold_http_post_s"), 3),
                       fmt_bytes(num(r, "cold_http_post_bytes_read")), mrate(num(r, "http_batch_lps_median")),
                       f2(num(r, "cold_http_stream_s"), 3),
                       fmt_bytes(num(r, "cold_http_stream_bytes")), fmt_bytes(num(r, "payload_bytes")),
                       fmt_bytes(num(r, "decoded_bytes")), f2(num(r, "decoded_over_payload")),
                       fmt_bytes(num(r, "cache_peak_bytes")), f2(num(r, "lookup_rss_mib"), 0)] for r in rows]))
    out += ["", end]
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", nargs="+", help="results.json files written by `shadowtiles bench`")
    ap.add_argument("--md", default="BENCHMARKS.md")
    ap.add_argument("--note", action="append", default=[], help="a note printed under the runs (repeatable)")
    ap.add_argument("--block", default="queries", choices=sorted(BLOCKS), help="which section to write")
    args = ap.parse_args()
    rows, runs = load(args.results)
    if not rows:
        sys.exit("no rows in " + ", ".join(args.results))
    text = open(args.md).read() if os.path.exists(args.md) else "# Benchmarks\n"
    block = section(rows, runs, args.note, args.block)
    begin, end = markers(args.block)
    pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
    if pattern.search(text):
        text = pattern.sub(lambda _: block, text)
    else:  # first time: before the contract-size block if there is one, else at the end
        at = text.find("<!-- contract-sizes:begin -->")
        text = text[:at] + block + "\n\n" + text[at:] if at >= 0 else text.rstrip("\n") + "\n\n" + block + "\n"
    with open(args.md, "w") as f:
        f.write(text)
    print(f"wrote the {args.block} section of {args.md}: {len(rows)} rows from {len(runs)} runs")


if __name__ == "__main__":
    main()
