#!/usr/bin/python3
"""Seed corpora for the fuzz targets (fuzz/), from real builds of the shared scenes.

Builds two small stores with every method (terragen: terrain, fzk_haus: a building) with the
Release CLI, reads their LMDB records with mdb_dump, and writes per target:
  fuzz_blob            tile and top-tree blobs as stored (first byte 0: checksum kept)
  fuzz_tile_<method>   the decompressed payloads of that method's tiles
  fuzz_preview         preview records (first byte: expected method)
  fuzz_store_meta      the stores' meta records
  fuzz_request_parsing query strings, JSON and binary batches on points inside the stores
  fuzz_http            whole HTTP requests against the terragen store (its path is printed)
  fuzz_scene_loader    a 9 x 9 cut of the real Terragen file as .ter, ascii/binary PLY and OFF
Usage: fuzz_corpus.py CLI WORKDIR  (corpora in WORKDIR/corpus/<target>, stores in WORKDIR/stores)
Nothing here is committed: it is regenerated in seconds.
"""
import ctypes
import json
import os
import shutil
import struct
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "..", "shared", "scenes")
METHODS = ["raw", "mh", "mmh", "dagmh", "cpvs", "sst"]  # method byte = index + 1 (store/method.hpp)
PER_METHOD = 24

zstd = ctypes.CDLL("libzstd.so.1")
zstd.ZSTD_decompress.restype = ctypes.c_size_t
zstd.ZSTD_decompress.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t]
zstd.ZSTD_isError.argtypes = [ctypes.c_size_t]


def unblob(blob):
    raw_size, payload_size = struct.unpack_from("<QQ", blob, 8)
    out = ctypes.create_string_buffer(raw_size)
    n = zstd.ZSTD_decompress(out, raw_size, blob[32:], payload_size)
    if zstd.ZSTD_isError(n) or n != raw_size:
        raise RuntimeError("zstd failed on a stored blob")
    return out.raw[:raw_size]


def dump(store, database):
    """(key, value) pairs of one LMDB database, through mdb_dump's hex output."""
    text = subprocess.run(["mdb_dump", "-s", database, store], check=True, capture_output=True, text=True).stdout
    lines = text.split("HEADER=END\n", 1)[1].split("DATA=END", 1)[0].split()
    return [(bytes.fromhex(lines[i]), bytes.fromhex(lines[i + 1])) for i in range(0, len(lines) - 1, 2)]


def build(cli, scene, out, extra):
    if os.path.isdir(out):
        shutil.rmtree(out)
    subprocess.run([cli, "build", scene, "--out", out, "-r", "256", "-m", ",".join(METHODS), "-j", "1"] + extra,
                   check=True, stdout=subprocess.DEVNULL)


def spread(items, count):
    """`count` items spread over a list sorted by size: small, large and between."""
    items = sorted(items, key=len)
    if len(items) <= count:
        return items
    return [items[i * (len(items) - 1) // (count - 1)] for i in range(count)]


def write(corpus, target, name, data):
    d = os.path.join(corpus, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def http_request(method, path, body=b"", headers=()):
    lines = [f"{method} {path} HTTP/1.1", "Host: 127.0.0.1"] + list(headers)
    if body or method == "POST":
        lines.append(f"Content-Length: {len(body)}")
    return ("\r\n".join(lines) + "\r\n\r\n").encode() + body


def terragen_cut(path, n=9):
    """The real .ter's first n x n samples, as .ter bytes and as (vertices, faces) in metres."""
    data = open(path, "rb").read()
    xpts = struct.unpack_from("<h", data, data.index(b"XPTS") + 4)[0]
    scal = struct.unpack_from("<3f", data, data.index(b"SCAL") + 4)
    altw = data.index(b"ALTW")
    scale, base = struct.unpack_from("<hh", data, altw + 4)
    samples = [struct.unpack_from("<h", data, altw + 8 + 2 * (y * xpts + x))[0] for y in range(n) for x in range(n)]
    ter = (b"TERRAGENTERRAIN " + b"SIZE" + struct.pack("<hh", n - 1, 0) + b"XPTS" + struct.pack("<hh", n, 0) +
           b"YPTS" + struct.pack("<hh", n, 0) + b"SCAL" + struct.pack("<3f", *scal) + b"ALTW" +
           struct.pack("<hh", scale, base) + struct.pack(f"<{n * n}h", *samples) + b"EOF ")
    vertices = [(x * scal[0], y * scal[1], scal[2] * (base + samples[y * n + x] * scale / 65536.0))
                for y in range(n) for x in range(n)]
    faces = []
    for y in range(n - 1):
        for x in range(n - 1):
            a = y * n + x
            faces += [(a, a + 1, a + n + 1), (a, a + n + 1, a + n)]
    return ter, vertices, faces


def scene_seeds(corpus):
    ter, vertices, faces = terragen_cut(os.path.join(SCENES, "terragen", "RealisticTerrain.ter"))
    ply_head = (f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\nproperty float x\nproperty float y\n"
                f"property float z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    ply = ply_head + "".join(f"{x:.3f} {y:.3f} {z:.3f}\n" for x, y, z in vertices) + \
        "".join(f"3 {a} {b} {c}\n" for a, b, c in faces)
    binary = ply_head.replace("ascii", "binary_little_endian").encode() + \
        b"".join(struct.pack("<3f", *v) for v in vertices) + b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    off = f"OFF\n{len(vertices)} {len(faces)} 0\n" + "".join(f"{x:.3f} {y:.3f} {z:.3f}\n" for x, y, z in vertices) + \
        "".join(f"3 {a} {b} {c}\n" for a, b, c in faces)
    # First byte: extension (0 .ply, 1 .off, 2 .ter), +4 declares every mesh a heightfield.
    write(corpus, "fuzz_scene_loader", "ascii.ply", b"\x00" + ply.encode())
    write(corpus, "fuzz_scene_loader", "binary.ply", b"\x04" + binary)
    write(corpus, "fuzz_scene_loader", "terrain.off", b"\x01" + off.encode())
    write(corpus, "fuzz_scene_loader", "terrain.ter", b"\x06" + ter)


def main():
    cli, work = sys.argv[1], sys.argv[2]
    corpus = os.path.join(work, "corpus")
    stores = os.path.join(work, "stores")
    if os.path.isdir(corpus):
        shutil.rmtree(corpus)
    os.makedirs(stores, exist_ok=True)
    builds = {
        "terragen": (os.path.join(SCENES, "terragen", "RealisticTerrain.ter"), ["--tile", "32", "--heightfield", "*"]),
        "fzk_haus": (os.path.join(SCENES, "fzk_haus", "fzk_haus.obj"), ["--tile", "64", "--up", "y"]),
    }
    metas = {}
    for name, (scene, extra) in builds.items():
        store = os.path.join(stores, name)
        build(cli, scene, store, extra)
        by_method = {m: [] for m in METHODS}
        for key, blob in dump(store, "tiles"):
            by_method[METHODS[key[0] - 1]].append((key, blob))
        for method, records in by_method.items():
            chosen = spread([blob for _, blob in records], PER_METHOD)
            for i, blob in enumerate(chosen):
                write(corpus, "fuzz_blob", f"{name}-{method}-{i}", b"\x00" + blob)
                write(corpus, "fuzz_tile_" + method, f"{name}-{i}", unblob(blob))
        for key, blob in dump(store, "top"):
            write(corpus, "fuzz_blob", f"{name}-{key.decode(errors='replace').replace('/', '-')}", b"\x00" + blob)
        previews = dump(store, "preview")
        for i, (key, blob) in enumerate(previews[:: max(1, len(previews) // PER_METHOD)]):
            write(corpus, "fuzz_preview", f"{name}-{i}", bytes([(key[0] - 1) << 1]) + blob)
        for key, value in dump(store, "meta"):
            if key == b"build":
                write(corpus, "fuzz_store_meta", name, value)
                metas[name] = json.loads(value)
    request_seeds(corpus, metas["terragen"], dump(os.path.join(stores, "terragen"), "tiles"))
    scene_seeds(corpus)
    print(os.path.join(stores, "terragen"))


def request_seeds(corpus, meta, tiles):
    lo, hi = meta["scene"]["bounds_min"], meta["scene"]["bounds_max"]
    points = [[lo[0] + (hi[0] - lo[0]) * f, lo[1] + (hi[1] - lo[1]) * g, hi[2]] for f, g in
              [(0.5, 0.5), (0.1, 0.9), (0.33, 0.66), (1.5, 0.5)]]
    body = json.dumps({"points": points, "pcf": 3, "method": "mh"}).encode()
    binary = b"".join(struct.pack("<3f", *p) for p in points)
    x, y, z = points[0]
    query = f"x={x}&y={y}&z={z}"
    seeds = {
        "json-batch": b"\x00" + body,
        "json-batch-options": b"\x00" + json.dumps({"points": points[:2], "level": 2, "bias": 0.5, "method": "dagmh"}).encode(),
        "binary": b"\x01" + binary,
        "query": b"\x02" + query.encode(),
        "query-options": b"\x02" + (query + "&pcf=5&method=mmh&level=3&bias=0.25").encode(),
        "options-json": b"\x03" + json.dumps({"pcf": 7, "method": "sst", "level": 1, "bias": 1e-3}).encode(),
        "number": b"\x04" + b"-12.5e3",
        "unsigned": b"\x04" + b"4096",
    }
    for name, data in seeds.items():
        write(corpus, "fuzz_request_parsing", name, data)
    build_id = meta["config_hash"]
    requests = {
        "healthz": http_request("GET", "/healthz"),
        "meta": http_request("GET", "/v1/meta"),
        "build": http_request("GET", "/v1/build", headers=[f'If-None-Match: "{build_id}"']),
        "metrics": http_request("GET", "/metrics"),
        "point": http_request("GET", "/v1/shadow?" + query),
        "pcf": http_request("GET", "/v1/shadow?" + query + "&pcf=3&method=dagmh&level=2&bias=0.5"),
        "batch-json": http_request("POST", "/v1/shadow", body, ["Content-Type: application/json"]),
        "batch-binary": http_request("POST", "/v1/shadow?pcf=3&method=cpvs", binary,
                                     ["Content-Type: application/octet-stream"]),
        "expect-continue": http_request("POST", "/v1/shadow", body,
                                        ["Content-Type: application/json", "Expect: 100-continue"]),
        "skiplist": http_request("GET", "/v1/skiplist?method=mmh"),
        "texel": http_request("GET", "/v1/texel?u=17&v=200"),
        "render": http_request("GET", "/v1/render/mh/0/0/0.png?layer=diff&against=raw"),
        "pipelined": http_request("GET", "/v1/shadow?" + query + "&method=sst") + http_request("HEAD", "/healthz"),
        "options": http_request("OPTIONS", "/v1/shadow", headers=["Origin: http://example.org"]),
    }
    for i, (key, _) in enumerate(tiles[:: max(1, len(tiles) // 12)]):
        method, level = METHODS[key[0] - 1], key[1]
        tx, ty = struct.unpack(">II", key[2:10])
        path = f"/v1/tiles/{method}/{level}/{tx}/{ty}" if i % 2 else f"/v1/builds/{build_id}/tiles/{method}/{level}/{tx}/{ty}"
        requests[f"tile-{i}"] = http_request("GET", path)
    for name, data in requests.items():
        write(corpus, "fuzz_http", name, data)


if __name__ == "__main__":
    main()
