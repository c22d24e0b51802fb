#!/usr/bin/env python3
"""Hostile clients, answer sampling and RSS watch for bench/mixed_load.sh (issue 18).

While wrk loads the server with valid requests, this driver runs for DURATION seconds:
  - HOSTILE worker threads (loopback only), each sending one malformed or abusive request at a time,
    at most MAX_HOSTILE requests in all: bad query strings, malformed request lines, binary garbage,
    bad JSON, deep JSON, garbage and NaN binary batches, oversized Content-Length, chunked bodies,
    header floods, stalled bodies, trickled headers (at most TRICKLERS at once), clients that hang up
    mid-request. Every answer must be a 4xx (a client that hangs up expects none); a 5xx, an answer
    missing where one is due, or a wait past the bound is a failure;
  - one sampler that asks, at random moments, point GETs and binary batches at fixed random points
    of the scene's box for each method, and keeps every answer;
  - one watcher that reads the server's RSS (/proc/PID/status) and its tile cache gauge (/metrics)
    every second.
Then it compares every sampled answer with the local decoder (`shadowtiles query STORE --json`, the
same points), reads /metrics for 5xx answers, and prints one summary line per figure plus a JSON
summary (--json) that bench/mixed_load.sh turns into its "mixed load:" line. Exit 1 when any check fails.

Usage: mixed_load_driver.py --port P --pid PID --store DIR --cli PATH --duration S [--json OUT]
"""
import argparse
import json
import os
import random
import re
import select
import socket
import struct
import subprocess
import sys
import threading
import time
import urllib.request

HOST = "127.0.0.1"
MAX_HOSTILE = 50000
HOSTILE_WORKERS = 4
TRICKLERS = 2
ANSWER_BOUND_S = 20.0  # the longest wait for any answer (the slowest: a trickle cut at read_timeout_s)
SAMPLE_POINTS = 200    # fixed random points per method, each compared with the decoder


def parse_args():
    p = argparse.ArgumentParser()
    p.add_argument("--port", type=int, required=True)
    p.add_argument("--pid", type=int, required=True)
    p.add_argument("--store", required=True)
    p.add_argument("--cli", required=True)
    p.add_argument("--duration", type=float, required=True)
    p.add_argument("--warmup", type=float, default=None,
                   help="seconds of load before RSS is taken as 'filled' (default: a fifth of the run, >= 3)")
    p.add_argument("--json", default=None)
    return p.parse_args()


def http_get(port, path, timeout=10):
    with urllib.request.urlopen(f"http://{HOST}:{port}{path}", timeout=timeout) as r:
        return r.status, r.read()


def metrics(port):
    _, body = http_get(port, "/metrics")
    return body.decode()


def rss_kib(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


# ---- one raw exchange ------------------------------------------------------------------------

def exchange(port, payload_parts, pause=0.0, read=True, timeout=ANSWER_BOUND_S):
    """Sends the parts (pausing `pause` s between them), then reads until the server closes or the
    answer is complete. Returns (status or None, seconds)."""
    start = time.monotonic()
    s = socket.create_connection((HOST, port), timeout=timeout)
    try:
        for part in payload_parts:
            if pause and select.select([s], [], [], 0)[0]:
                break  # answered (cut off) while still trickling: read the answer
            try:
                s.sendall(part)
            except OSError:
                break  # the server already answered and closed (an early 413 / 408)
            if pause:
                time.sleep(pause)
        if not read:
            return None, time.monotonic() - start
        s.settimeout(max(0.1, timeout - (time.monotonic() - start)))
        data = b""
        while True:
            try:
                chunk = s.recv(65536)
            except socket.timeout:
                raise TimeoutError("no complete answer in time")
            except ConnectionResetError:
                break
            if not chunk:
                break
            data += chunk
            head, sep, body = data.partition(b"\r\n\r\n")
            if sep:
                m = re.search(rb"\r\ncontent-length:\s*(\d+)", head, re.I)
                if m and len(body) >= int(m.group(1)):
                    break
        m = re.match(rb"HTTP/1\.[01] (\d{3})", data)
        return (int(m.group(1)) if m else None), time.monotonic() - start
    finally:
        s.close()


def request(method, path, body=b"", headers=()):
    head = f"{method} {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
    for h in headers:
        head += h + "\r\n"
    if body or method == "POST":
        if not any(h.lower().startswith("content-length") for h in headers):
            head += f"Content-Length: {len(body)}\r\n"
    return head.encode() + b"\r\n" + body


# ---- hostile kinds: each returns (status or None, seconds, expected answer: "4xx", "4xx or 200"
# (a random batch can be valid), or None when the client hangs up and expects nothing) ------------

def hostile_kinds(port, rng, trickle_gate):
    bad_gets = [
        "/v1/shadow", "/v1/shadow?x=1&y=2", "/v1/shadow?x=abc&y=0&z=0", "/v1/shadow?x=nan&y=0&z=0",
        "/v1/shadow?x=inf&y=0&z=0", "/v1/shadow?x=1e999&y=0&z=0", "/v1/shadow?x=0&y=0&z=0&x=1",
        "/v1/shadow?x=0&y=0&z=0&pcf=2", "/v1/shadow?x=0&y=0&z=0&pcf=99999999999999999999",
        "/v1/shadow?x=0&y=0&z=0&method=bogus", "/v1/shadow?x=0&y=0&z=0&level=999",
        "/v1/shadow?x=0&y=0&z=0&bias=-1", "/v1/shadow?x=%zz&y=0&z=0", "/v1/tiles/raw/0/x/1",
        "/v1/tiles/raw/99/0/0", "/v1/tiles/bogus/0/0/0", "/v1/tiles/raw/0/99999999999/0", "/v1/nope",
        "/v1/render/raw/99/0/0.png", "/v1/render/raw/0/0/0.png?layer=heat", "/v1/texel?u=a&v=0",
        "/v1/builds/nope/tiles/raw/0/0/0", "/inspector/leaflet/../../etc/passwd",
        "/" + "a" * 7000, "/v1/shadow?x=" + "9" * 7000 + "&y=0&z=0",
    ]
    bad_json = [b"{", b"", b"[]", b"{}", b'{"points": 3}', b'{"points": [[0, 0]]}', b'{"points": [[0, "a", 0]]}',
                b'{"points": [[0, 1e999, 0]]}', b'{"points": [[0, NaN, 0]]}', b'{"points": [[0,0,0]], "pcf": 4}',
                b'{"points": [[0,0,0]], "method": "bogus"}', b'{"points": [[0,0,0]], "extra": 1}',
                b'{"points": [[0,0,0]]} trailing', b"[" * 100000, b"\xff\xfe garbage \x00"]

    def bad_get():
        return exchange(port, [request("GET", rng.choice(bad_gets))]) + ("4xx",)

    def bad_method():
        return exchange(port, [request(rng.choice(["DELETE", "PUT", "PATCH"]), "/v1/meta", b"x")]) + ("4xx",)

    def garbage_line():
        junk = bytes(rng.randrange(1, 256) for _ in range(rng.randrange(1, 200))).replace(b"\r\n", b"  ")
        return exchange(port, [junk + b"\r\n\r\n"]) + ("4xx",)

    def bad_version():
        return exchange(port, [b"GET /healthz HTTP/9.9\r\nHost: x\r\n\r\n"]) + ("4xx",)

    def json_batch():
        return exchange(port, [request("POST", "/v1/shadow", rng.choice(bad_json),
                                       ["Content-Type: application/json"])]) + ("4xx",)

    def garbage_batch():
        n = rng.randrange(0, 400)
        body = os.urandom(n)  # not a multiple of 12 most of the time (400); else random floats: a NaN
        # or infinity is a 400, finite points are a valid batch (200)
        return exchange(port, [request("POST", "/v1/shadow", body, ["Content-Type: application/octet-stream"])]) + (
            "4xx" if n % 12 else "4xx or 200",)

    def nan_batch():
        body = struct.pack("<3f", 0.0, float("nan"), 0.0) * rng.randrange(1, 50)
        return exchange(port, [request("POST", "/v1/shadow", body, ["Content-Type: application/octet-stream"])]) + ("4xx",)

    def oversized_length():
        return exchange(port, [request("POST", "/v1/shadow", b"", ["Content-Type: application/octet-stream",
                                                                 "Content-Length: 99999999999"])]) + ("4xx",)

    def chunked():
        head = (b"POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                b"Transfer-Encoding: chunked\r\n\r\n")
        return exchange(port, [head, b"5\r\n{\"poi\r\n"]) + ("4xx",)

    def header_flood():
        head = b"GET /healthz HTTP/1.1\r\nHost: x\r\n" + b"X-Flood: " + b"a" * 70000 + b"\r\n\r\n"
        return exchange(port, [head]) + ("4xx",)

    def unsupported_type():
        return exchange(port, [request("POST", "/v1/shadow", b"x=1", ["Content-Type: text/plain"])]) + ("4xx",)

    def stalled_body():
        head = (b"POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                b"Content-Length: 1000\r\n\r\n{\"points\"")
        return exchange(port, [head]) + ("4xx",)  # cut off at body_timeout_s: 408

    def trickle():
        # One byte every 100 ms of a header that never ends: cut off at read_timeout_s with 408.
        if not trickle_gate.acquire(blocking=False):
            return bad_get() + ("bad_get",)  # enough tricklers already: counted as what was sent
        try:
            parts = [b"GET /healthz HTTP/1.1\r\nHost: x\r\n"] + [b"X"] * 200
            return exchange(port, parts, pause=0.1) + ("4xx",)
        finally:
            trickle_gate.release()

    def hang_up():
        status, seconds = exchange(port, [b"POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Len"], read=False)
        return status, seconds, None

    weighted = [(bad_get, 30), (bad_method, 4), (garbage_line, 6), (bad_version, 2), (json_batch, 12),
                (garbage_batch, 10), (nan_batch, 4), (oversized_length, 6), (chunked, 3), (header_flood, 2),
                (unsupported_type, 3), (stalled_body, 1), (trickle, 1), (hang_up, 4)]
    return weighted


class HostileStats:
    def __init__(self):
        self.lock = threading.Lock()
        self.by_kind = {}      # kind -> [count, statuses{}]
        self.sent = 0
        self.failures = []     # descriptions
        self.worst_s = {}      # kind -> worst seconds

    def record(self, kind, status, seconds, expected):
        with self.lock:
            self.sent += 1
            entry = self.by_kind.setdefault(kind, [0, {}])
            entry[0] += 1
            entry[1][status] = entry[1].get(status, 0) + 1
            self.worst_s[kind] = max(self.worst_s.get(kind, 0.0), seconds)
            ok = (expected is None or (status is not None and 400 <= status <= 499) or
                  (expected == "4xx or 200" and status == 200))
            if not ok:
                if len(self.failures) < 50:
                    self.failures.append(f"{kind}: status {status} after {seconds:.2f} s")


def hostile_worker(port, seed, stop, stats, trickle_gate):
    rng = random.Random(seed)
    kinds = hostile_kinds(port, rng, trickle_gate)
    fns = [k for k, _ in kinds]
    weights = [w for _, w in kinds]
    while not stop.is_set():
        with stats.lock:
            if stats.sent >= MAX_HOSTILE:
                return
        fn = rng.choices(fns, weights)[0]
        kind = fn.__name__
        try:
            status, seconds, expected, *sent_as = fn()
            kind = sent_as[0] if sent_as else kind
        except (TimeoutError, socket.timeout):
            status, seconds, expected = None, ANSWER_BOUND_S, "4xx"
        except ConnectionRefusedError:
            status, seconds, expected = None, 0.0, "4xx"
        stats.record(kind, status, seconds, expected)


# ---- sampled valid answers -------------------------------------------------------------------

def sample_points(meta, seed=11):
    lo, hi = meta["shadow"]["world_bounds"]["min"], meta["shadow"]["world_bounds"]["max"]
    rng = random.Random(seed)
    points = []
    for _ in range(SAMPLE_POINTS):
        # float32 values, so a binary batch and a decimal query ask exactly the same point
        p = [struct.unpack("<f", struct.pack("<f", rng.uniform(lo[i], hi[i])))[0] for i in range(3)]
        points.append(p)
    return points


def sampler(port, methods, points, stop, answers, errors):
    """answers[(method, index)] -> list of lit values seen (1.0 / 0.0), from GETs and batches."""
    rng = random.Random(5)
    while not stop.is_set():
        method = rng.choice(methods)
        try:
            if rng.random() < 0.5:
                i = rng.randrange(len(points))
                x, y, z = points[i]
                status, body = http_get(port, f"/v1/shadow?x={x!r}&y={y!r}&z={z!r}&method={method}")
                answers.setdefault((method, i), []).append(float(json.loads(body)["lit"]))
            else:
                idx = rng.sample(range(len(points)), 32)
                body = b"".join(struct.pack("<3f", *points[i]) for i in idx)
                req = urllib.request.Request(f"http://{HOST}:{port}/v1/shadow?method={method}", data=body,
                                             headers={"Content-Type": "application/octet-stream"})
                with urllib.request.urlopen(req, timeout=10) as r:
                    lit = struct.unpack(f"<{len(idx)}f", r.read())
                for i, v in zip(idx, lit):
                    answers.setdefault((method, i), []).append(v)
        except Exception as e:  # a valid request must never fail
            errors.append(f"sampled {method} query failed: {e!r}")
        stop.wait(rng.uniform(0.02, 0.1))


def decoder_answers(cli, store, method, points):
    args = [cli, "query", store, "--method", method, "--json", "-q"]
    for p in points:
        args += ["--point", ",".join(repr(v) for v in p)]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    return [1.0 if row["lit"] else 0.0 for row in json.loads(out)]


# ---- main ------------------------------------------------------------------------------------

def main():
    args = parse_args()
    warmup = args.warmup if args.warmup is not None else max(3.0, args.duration / 5)
    meta = json.loads(http_get(args.port, "/v1/meta")[1])
    methods = meta["shadow"]["methods"]
    points = sample_points(meta)

    stop = threading.Event()
    stats = HostileStats()
    trickle_gate = threading.Semaphore(TRICKLERS)
    answers, sample_errors = {}, []
    samples = []  # (t, rss KiB, cache bytes)
    start = time.monotonic()

    def watch():
        while not stop.is_set():
            try:
                m = metrics(args.port)
                cache = int(re.search(r"^shadowtiles_tile_cache_bytes (\d+)", m, re.M).group(1))
                samples.append((time.monotonic() - start, rss_kib(args.pid), cache))
            except Exception as e:
                sample_errors.append(f"watcher: {e!r}")
            stop.wait(1.0)

    threads = [threading.Thread(target=hostile_worker, args=(args.port, 100 + i, stop, stats, trickle_gate))
               for i in range(HOSTILE_WORKERS)]
    threads.append(threading.Thread(target=sampler, args=(args.port, methods, points, stop, answers, sample_errors)))
    threads.append(threading.Thread(target=watch))
    for t in threads:
        t.start()
    time.sleep(args.duration)
    stop.set()
    for t in threads:
        t.join(timeout=ANSWER_BOUND_S + 5)
    hung = [t for t in threads if t.is_alive()]
    final_rss = rss_kib(args.pid)
    samples.append((time.monotonic() - start, final_rss, samples[-1][2] if samples else 0))

    failures = []
    if hung:
        failures.append(f"{len(hung)} driver threads still waiting for an answer")
    failures += stats.failures
    failures += sample_errors[:20]

    # Every sampled answer equals the decoder's, for every time it was asked.
    compared = differ = 0
    for method in methods:
        expected = decoder_answers(args.cli, args.store, method, points)
        for i, want in enumerate(expected):
            for got in answers.get((method, i), []):
                compared += 1
                if got != want:
                    differ += 1
                    if differ <= 10:
                        failures.append(f"{method} point {points[i]}: server {got}, decoder {want}")

    # 5xx from the server's own counts (every route, every client: wrk, hostile, sampler).
    m = metrics(args.port)
    server_5xx = sum(int(c) for s, c in re.findall(r'^shadowtiles_http_requests_total\{[^}]*status="(5\d\d)"\} (\d+)', m, re.M))
    requests_total = sum(int(c) for c in re.findall(r'^shadowtiles_http_requests_total\{[^}]*\} (\d+)', m, re.M))
    if server_5xx:
        failures.append(f"{server_5xx} answers with a 5xx status (/metrics)")

    # RSS once the cache has filled (the first sample past the warm-up whose cache gauge is at the
    # run's highest) against RSS at the end.
    top_cache = max((c for _, _, c in samples), default=0)
    filled = next(((t, r) for t, r, c in samples if t >= warmup and c >= 0.95 * top_cache), None)
    if filled is None:
        failures.append("the tile cache never filled during the run")
        filled = samples[-1][:2] if samples else (0, final_rss)
    growth = (final_rss - filled[1]) / filled[1] if filled[1] else 0
    if abs(growth) > 0.10:
        failures.append(f"RSS moved {growth * 100:+.1f} % from {filled[1] / 1024:.1f} MiB (cache filled, t={filled[0]:.0f} s) "
                        f"to {final_rss / 1024:.1f} MiB at the end")
    peak = max(r for _, r, _ in samples)

    hostile_expected_answers = sum(n for k, (n, _) in stats.by_kind.items() if k != "hang_up")
    print(f"driver: {args.duration:.0f} s; hostile requests {stats.sent} ({len(stats.by_kind)} kinds, "
          f"{len(stats.failures)} not answered 4xx in time); server answers {requests_total}, 5xx {server_5xx}; "
          f"sampled answers compared with the decoder {compared} ({differ} differ); RSS cache filled "
          f"{filled[1] / 1024:.1f} MiB (t={filled[0]:.0f} s), end {final_rss / 1024:.1f} MiB ({growth * 100:+.1f} %), "
          f"peak {peak / 1024:.1f} MiB")
    for kind, (n, statuses) in sorted(stats.by_kind.items()):
        shown = ", ".join(f"{s}: {c}" for s, c in sorted(statuses.items(), key=lambda kv: str(kv[0])))
        print(f"  {kind:<18} {n:6d}   {shown}   worst {stats.worst_s[kind] * 1e3:.0f} ms")
    for f in failures:
        print(f"FAIL {f}", file=sys.stderr)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"duration_s": args.duration, "hostile_requests": stats.sent,
                       "hostile_answers_expected": hostile_expected_answers,
                       "hostile_by_kind": {k: v[0] for k, v in stats.by_kind.items()},
                       "server_requests": requests_total, "server_5xx": server_5xx, "compared": compared,
                       "differ": differ, "rss_filled_kib": filled[1], "rss_filled_at_s": filled[0],
                       "rss_end_kib": final_rss, "rss_peak_kib": peak, "rss_change": growth,
                       "failures": failures}, f, indent=1)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
