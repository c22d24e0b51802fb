/* shadowtiles.h: the C API of the shadowtiles client (libshadowtiles.so.1). Plain C99.
 *
 * Opens a shadow-map build (a local store directory, or a `shadowtiles serve` URL streamed on demand)
 * and answers "is this world point lit?" for single points, PCF kernels and batches, from the same
 * decoder as the C++ ShadowMap and the CLI. This is the surface engines bind (P/Invoke, FFI, ctypes).
 *
 * Errors: every fallible function returns a shadowtiles_status; SHADOWTILES_OK is 0. On failure the
 * message is available from shadowtiles_last_error() on the failing thread until that thread's next
 * failing call. Output parameters are written only on success (batches: all or nothing).
 *
 * Memory: the caller owns every buffer it passes in; the library allocates nothing the caller must
 * free except the map itself, released by shadowtiles_close(). Strings returned by the library are
 * owned by it (the map, or the calling thread for error messages).
 *
 * Thread safety: every function may be called concurrently from any threads, on the same map too,
 * except shadowtiles_close(), which must not overlap any other call on that map.
 *
 * ABI: stable within soname libshadowtiles.so.1 (docs/c-api.md): functions and the layout of the
 * structs below are only ever added, never changed. SHADOWTILES_ABI_VERSION names the soname major.
 */
#ifndef SHADOWTILES_H
#define SHADOWTILES_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(SHADOWTILES_BUILDING_C_API)
#define SHADOWTILES_API __attribute__((visibility("default")))
#else
#define SHADOWTILES_API
#endif

#define SHADOWTILES_ABI_VERSION 1

typedef enum shadowtiles_status {
  SHADOWTILES_OK = 0,
  SHADOWTILES_INVALID_INPUT = 1, /* bad argument: NULL pointer, non-finite point, unknown method, ... */
  SHADOWTILES_CORRUPT_DATA = 2,  /* a stored record fails its checks: never answered from */
  SHADOWTILES_NOT_FOUND = 3,     /* no store at the path, no build on the server */
  SHADOWTILES_IO_ERROR = 4,      /* the OS, LMDB or the network refused */
  SHADOWTILES_OUT_OF_SPACE = 5,
  SHADOWTILES_UNSUPPORTED = 6,   /* valid but not servable: a method the build lacks, a newer format */
  SHADOWTILES_OUT_OF_MEMORY = 7,
  SHADOWTILES_INTERNAL = 8       /* a bug: please report the message */
} shadowtiles_status;

/* An open build. Opaque. */
typedef struct shadowtiles_map shadowtiles_map;

/* One point's answer. */
typedef struct shadowtiles_answer {
  uint8_t lit;         /* 1 lit, 0 shadowed */
  uint8_t outside_map; /* 1: the point projects outside the map (answered lit) */
  uint8_t empty_tile;  /* 1: its tile holds no geometry (lit) */
  uint8_t reserved;
  float value;         /* stored shadow value compared with (normalised depth; +inf when none) */
  double u, v;         /* light-space texel coordinates */
  double depth;        /* normalised light-space depth, 0 near .. 1 far */
} shadowtiles_answer;

/* Sizes of an open build. */
typedef struct shadowtiles_info {
  uint32_t resolution;     /* texels per side of the whole map */
  uint32_t tile_size;      /* texels per side of a tile */
  uint32_t tiles_per_side; /* tiles are addressed x, y in [0, tiles_per_side) */
  uint32_t levels;         /* levels of detail: log2(resolution) + 1 */
  double default_bias;     /* world units, used when a call passes bias < 0 */
  double texel_size;       /* world units */
} shadowtiles_info;

/* Library version ("0.1.0") and the C ABI version (the soname major, SHADOWTILES_ABI_VERSION). */
SHADOWTILES_API const char* shadowtiles_version(void);
SHADOWTILES_API int shadowtiles_abi_version(void);
/* A status's name ("invalid_input"); "unknown" for values outside the enum. Static storage. */
SHADOWTILES_API const char* shadowtiles_status_name(shadowtiles_status status);
/* The message of the calling thread's last failure ("" if none). Valid until that thread's next
 * failing call; owned by the library. */
SHADOWTILES_API const char* shadowtiles_last_error(void);

/* Opens a store directory or a server URL (http://host:port). cache_bytes bounds the decoded-tile
 * cache (0: 256 MiB). On success *out is a map to release with shadowtiles_close(). */
SHADOWTILES_API shadowtiles_status shadowtiles_open(const char* location, uint64_t cache_bytes,
                                                    shadowtiles_map** out);
/* Releases the map (NULL is ignored). No call on it may be running or follow. */
SHADOWTILES_API void shadowtiles_close(shadowtiles_map* map);

/* The build's meta record as JSON (light frame, sizes, methods, default bias...), NUL-terminated,
 * owned by the map and valid until shadowtiles_close(). */
SHADOWTILES_API shadowtiles_status shadowtiles_meta_json(const shadowtiles_map* map, const char** json);
SHADOWTILES_API shadowtiles_status shadowtiles_get_info(const shadowtiles_map* map, shadowtiles_info* info);

/* Methods are named by strings: "mh", "mmh", "dagmh", "raw", "cpvs", "sst"; NULL or "" = the
 * build's default (its first). bias: world units, < 0 = the build's default. */

/* Is the world point (x, y, z) = point[0..2] lit? */
SHADOWTILES_API shadowtiles_status shadowtiles_query(const shadowtiles_map* map, const char* method,
                                                     const double point[3], double bias,
                                                     shadowtiles_answer* answer);
/* Percentage-closer filtering: the lit fraction of the kernel x kernel texels around the point
 * (kernel odd, 1..63). answer may be NULL. */
SHADOWTILES_API shadowtiles_status shadowtiles_query_pcf(const shadowtiles_map* map, const char* method,
                                                         const double point[3], uint32_t kernel, double bias,
                                                         double* lit_fraction, shadowtiles_answer* answer);
/* count points (xyz triples, 3 * count doubles, count < 2^32). threads: 0 = one per core. Outputs
 * of count entries each; lit is required, values and outside_map may be NULL. With values NULL the
 * batch path answers (points sorted by tile and Morton order, shared tree walks); values asks one
 * full query per point. All or nothing: on an error no output is meaningful. */
SHADOWTILES_API shadowtiles_status shadowtiles_query_batch(const shadowtiles_map* map, const char* method,
                                                           const double* points, size_t count, double bias,
                                                           uint32_t threads, uint8_t* lit, float* values,
                                                           uint8_t* outside_map);
/* PCF over a batch (the batch path): lit_fractions[count], each a multiple of 1/kernel^2 rounded
 * to float precision. */
SHADOWTILES_API shadowtiles_status shadowtiles_query_pcf_batch(const shadowtiles_map* map, const char* method,
                                                               const double* points, size_t count,
                                                               uint32_t kernel, double bias, uint32_t threads,
                                                               double* lit_fractions);

/* The decoded values of tile (x, y): tile_size * tile_size floats, row-major (texel (u, v) at
 * v * tile_size + u), +inf for an empty tile. capacity: floats available at values. */
SHADOWTILES_API shadowtiles_status shadowtiles_tile_values(const shadowtiles_map* map, const char* method,
                                                           uint32_t x, uint32_t y, float* values,
                                                           size_t capacity);
/* The first surface the light meets at each texel centre of tile (x, y): world points (xyz, 3 floats
 * of double per texel, same order as shadowtiles_tile_values) from the stored lower bound (method
 * "raw", which the build must hold) and the light frame; hit[i] = 0 where the ray meets nothing
 * (point then undefined). capacity: texels available (tile_size^2 needed). These points are lit by
 * construction; receivers of a heightfield are best taken from an overhead build (docs/c-api.md). */
SHADOWTILES_API shadowtiles_status shadowtiles_surface_points(const shadowtiles_map* map, uint32_t x, uint32_t y,
                                                              double* points, uint8_t* hit, size_t capacity);

#ifdef __cplusplus
}
#endif

#endif /* SHADOWTILES_H */
