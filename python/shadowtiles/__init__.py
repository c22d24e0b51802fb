"""shadowtiles: lit/shadowed queries on compressed shadow maps, from Python with NumPy.

A thin ctypes layer over the stable C API (libshadowtiles.so.1, shadowtiles.h; docs/python.md says
why ctypes rather than pybind11). Batches go to the library in one call on the arrays' memory (no
copy, no per-point Python), and ctypes releases the GIL for the duration of every call.

    import shadowtiles
    with shadowtiles.open("/data/store") as m:           # or "http://127.0.0.1:8080"
        lit, values = m.query(points)                     # points: (N, 3) float64
        lit, _ = m.query(points, values=False)            # lit flags only: the sorted batch path
        fractions = m.pcf(points, 5)
        m.meta["resolution"], m.tile("mh", 0, 0)          # decoded values of a tile, (T, T) float32
        xyz = m.surface_points()                          # first-hit world points of every texel

Errors raise shadowtiles.Error (a subclass of RuntimeError) with the library's message and .code.
A Map may be used from several Python threads at once; close() must not overlap other calls.
"""
import ctypes
import ctypes.util
import json
import os

import numpy as np

__all__ = ["open", "Map", "Error", "library_version"]

_STATUS_NAMES = {1: "invalid_input", 2: "corrupt_data", 3: "not_found", 4: "io_error", 5: "out_of_space",
                 6: "unsupported", 7: "out_of_memory", 8: "internal"}


class Error(RuntimeError):
    """A failed library call: str(e) is the library's message, e.code its status name."""

    def __init__(self, code, message):
        super().__init__(message)
        self.code = _STATUS_NAMES.get(code, "unknown")
        self.status = code


class _Answer(ctypes.Structure):
    _fields_ = [("lit", ctypes.c_uint8), ("outside_map", ctypes.c_uint8), ("empty_tile", ctypes.c_uint8),
                ("reserved", ctypes.c_uint8), ("value", ctypes.c_float), ("u", ctypes.c_double),
                ("v", ctypes.c_double), ("depth", ctypes.c_double)]


class _Info(ctypes.Structure):
    _fields_ = [("resolution", ctypes.c_uint32), ("tile_size", ctypes.c_uint32),
                ("tiles_per_side", ctypes.c_uint32), ("levels", ctypes.c_uint32),
                ("default_bias", ctypes.c_double), ("texel_size", ctypes.c_double)]


def _library_path():
    explicit = os.environ.get("SHADOWTILES_LIBRARY")
    if explicit:
        return explicit
    try:  # written by `cmake --install`: where the library sits relative to this package
        from . import _install_paths
        candidate = os.path.normpath(os.path.join(os.path.dirname(__file__), _install_paths.LIBRARY_RELATIVE))
        if os.path.exists(candidate):
            return candidate
    except ImportError:
        pass
    return ctypes.util.find_library("shadowtiles") or "libshadowtiles.so.1"


def _load():
    lib = ctypes.CDLL(_library_path())  # CDLL, not PyDLL: the GIL is released during calls
    if lib.shadowtiles_abi_version() != 1:
        raise ImportError("libshadowtiles ABI %d, this module needs 1" % lib.shadowtiles_abi_version())
    P, c = ctypes.POINTER, ctypes
    map_p, dbl_p, u8_p, f32_p = c.c_void_p, P(c.c_double), P(c.c_uint8), P(c.c_float)
    sigs = {
        "shadowtiles_version": ([], c.c_char_p),
        "shadowtiles_last_error": ([], c.c_char_p),
        "shadowtiles_open": ([c.c_char_p, c.c_uint64, P(c.c_void_p)], c.c_int),
        "shadowtiles_close": ([map_p], None),
        "shadowtiles_meta_json": ([map_p, P(c.c_char_p)], c.c_int),
        "shadowtiles_get_info": ([map_p, P(_Info)], c.c_int),
        "shadowtiles_query": ([map_p, c.c_char_p, dbl_p, c.c_double, P(_Answer)], c.c_int),
        "shadowtiles_query_batch": ([map_p, c.c_char_p, dbl_p, c.c_size_t, c.c_double, c.c_uint32, u8_p, f32_p,
                                     u8_p], c.c_int),
        "shadowtiles_query_pcf_batch": ([map_p, c.c_char_p, dbl_p, c.c_size_t, c.c_uint32, c.c_double, c.c_uint32,
                                         dbl_p], c.c_int),
        "shadowtiles_tile_values": ([map_p, c.c_char_p, c.c_uint32, c.c_uint32, f32_p, c.c_size_t], c.c_int),
        "shadowtiles_surface_points": ([map_p, c.c_uint32, c.c_uint32, dbl_p, u8_p, c.c_size_t], c.c_int),
    }
    for name, (args, result) in sigs.items():
        fn = getattr(lib, name)
        fn.argtypes, fn.restype = args, result
    return lib


_lib = _load()


def library_version():
    return _lib.shadowtiles_version().decode()


def _check(status):
    if status != 0:
        raise Error(status, _lib.shadowtiles_last_error().decode("utf-8", "replace"))


def _ptr(array, ctype):
    return array.ctypes.data_as(ctypes.POINTER(ctype))


def _method(method):
    return None if method is None else str(method).encode()


def _bias(bias):
    return -1.0 if bias is None else float(bias)


def _points(points):
    array = np.ascontiguousarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError("points must be an (N, 3) array of x, y, z; got shape %s" % (array.shape,))
    return array


class Map:
    """An open build (store directory or server URL). Use shadowtiles.open()."""

    def __init__(self, location, cache_bytes=0):
        self._handle = None  # close() and __del__ work even when the open fails
        handle = ctypes.c_void_p()
        _check(_lib.shadowtiles_open(os.fsencode(location), int(cache_bytes), ctypes.byref(handle)))
        self._handle = handle
        text = ctypes.c_char_p()
        _check(_lib.shadowtiles_meta_json(handle, ctypes.byref(text)))
        self.meta = json.loads(text.value.decode())
        info = _Info()
        _check(_lib.shadowtiles_get_info(handle, ctypes.byref(info)))
        self.resolution, self.tile_size = info.resolution, info.tile_size
        self.tiles_per_side, self.levels = info.tiles_per_side, info.levels
        self.default_bias, self.texel_size = info.default_bias, info.texel_size
        self.methods = list(self.meta["methods"])

    def _h(self):
        if self._handle is None:
            raise Error(1, "the map is closed")
        return self._handle

    def close(self):
        if self._handle is not None:
            _lib.shadowtiles_close(self._handle)
            self._handle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def query(self, points, method=None, bias=None, threads=0, values=True):
        """Lit flags (bool, N) and stored values (float32, N) of (N, 3) float64 world points.

        values=False skips the values (returns (lit, None)) and takes the library's batch path
        (points sorted by tile and Morton order): the fast way to ask many points."""
        pts = _points(points)
        n = pts.shape[0]
        lit = np.empty(n, dtype=np.uint8)
        out = np.empty(n, dtype=np.float32) if values else None
        _check(_lib.shadowtiles_query_batch(self._h(), _method(method), _ptr(pts, ctypes.c_double), n, _bias(bias),
                                            int(threads), _ptr(lit, ctypes.c_uint8),
                                            _ptr(out, ctypes.c_float) if values else None, None))
        return lit.view(np.bool_), out

    def query_point(self, point, method=None, bias=None):
        """One point: a dict of lit, outside_map, empty_tile, value, u, v, depth."""
        p = np.ascontiguousarray(point, dtype=np.float64).reshape(3)
        a = _Answer()
        _check(_lib.shadowtiles_query(self._h(), _method(method), _ptr(p, ctypes.c_double), _bias(bias),
                                      ctypes.byref(a)))
        return {"lit": bool(a.lit), "outside_map": bool(a.outside_map), "empty_tile": bool(a.empty_tile),
                "value": a.value, "u": a.u, "v": a.v, "depth": a.depth}

    def pcf(self, points, k, method=None, bias=None, threads=0):
        """Lit fraction (float64, N) of the k x k texel kernel around each point (k odd)."""
        pts = _points(points)
        n = pts.shape[0]
        out = np.empty(n, dtype=np.float64)
        _check(_lib.shadowtiles_query_pcf_batch(self._h(), _method(method), _ptr(pts, ctypes.c_double), n, int(k),
                                                _bias(bias), int(threads), _ptr(out, ctypes.c_double)))
        return out

    def tile(self, method, x, y):
        """Decoded values of tile (x, y) as a (T, T) float32 array indexed [v, u] (+inf: empty)."""
        t = self.tile_size
        out = np.empty((t, t), dtype=np.float32)
        _check(_lib.shadowtiles_tile_values(self._h(), _method(method), int(x), int(y), _ptr(out, ctypes.c_float),
                                            out.size))
        return out

    def tile_surface_points(self, x, y):
        """World points (T, T, 3) of the first surface the light meets at tile (x, y)'s texel centres,
        and hit flags (T, T); needs method raw in the build."""
        t = self.tile_size
        pts = np.empty((t, t, 3), dtype=np.float64)
        hit = np.empty((t, t), dtype=np.uint8)
        _check(_lib.shadowtiles_surface_points(self._h(), int(x), int(y), _ptr(pts, ctypes.c_double),
                                               _ptr(hit, ctypes.c_uint8), hit.size))
        return pts, hit.view(np.bool_)

    def surface_points(self):
        """(N, 3) world points of the first hit under every texel of the map that meets geometry."""
        parts = []
        for y in range(self.tiles_per_side):
            for x in range(self.tiles_per_side):
                pts, hit = self.tile_surface_points(x, y)
                parts.append(pts[hit])
        return np.concatenate(parts) if parts else np.empty((0, 3))


def open(location, cache_bytes=0):  # noqa: A001 (the module's entry point, like gzip.open)
    """Opens a store directory or a server URL (http://host:port)."""
    return Map(location, cache_bytes)
