#!/usr/bin/python3
"""Python overhead: Map.query on N points (one call into the C API, one thread) vs the same points
answered by the C++ client (cpp-consumer --bench), in one run, best of REPEATS: lit flags only
(query(values=False) vs ShadowMap::query_batch) and with the stored values (query() vs a loop of
ShadowMap::query).

    bench_query.py STORE CPP_CONSUMER [--points 1000000] [--method mh] [--repeats 3]

Points: uniform over the terrain's receivers (receivers.py needs an overhead store) or, by default,
uniform in the scene bounds. Prints seconds and the ratio python / C++.
"""
import argparse
import os
import subprocess
import tempfile
import time

import numpy as np

import shadowtiles


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("store")
    parser.add_argument("cpp_consumer")
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--method", default="mh")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    with shadowtiles.open(args.store) as m, tempfile.TemporaryDirectory() as tmp:
        lo = np.array(m.meta["scene"]["bounds_min"])
        hi = np.array(m.meta["scene"]["bounds_max"])
        points = np.random.default_rng(7).uniform(lo, hi, size=(args.points, 3))
        path = os.path.join(tmp, "points.f64")
        points.tofile(path)
        m.query(points, args.method, threads=1)  # loads and decodes the tiles, as the C++ warm-up pass does
        python_s, python_lit_s, cpp_s, cpp_batch_s = [], [], [], []
        for _ in range(args.repeats):  # alternating, so load on the shared machine hits both alike
            start = time.perf_counter()
            lit, _ = m.query(points, args.method, threads=1)  # lit flags and values: per-point path
            python_s.append(time.perf_counter() - start)
            start = time.perf_counter()
            lit_only, _ = m.query(points, args.method, threads=1, values=False)  # the batch path
            python_lit_s.append(time.perf_counter() - start)
            out = subprocess.run([args.cpp_consumer, "--bench", args.store, path, args.method], check=True,
                                 capture_output=True, text=True).stdout.split()
            cpp_s.append(float(out[1]))
            cpp_batch_s.append(float(out[7]))
            if int(out[5]) != int(lit.sum()) or int(lit_only.sum()) != int(lit.sum()):
                raise SystemExit("C++ and Python disagree: %s vs %d lit" % (out[5], lit.sum()))
    print("points %d method %s, one thread, best of %d:" % (args.points, args.method, args.repeats))
    print("  lit only:   python query(values=False) %.3f s, C++ query_batch %.3f s, ratio %.2f"
          % (min(python_lit_s), min(cpp_batch_s), min(python_lit_s) / min(cpp_batch_s)))
    print("  with values: python query() %.3f s, C++ query() loop %.3f s, ratio %.2f"
          % (min(python_s), min(cpp_s), min(python_s) / min(cpp_s)))

if __name__ == "__main__":
    main()
