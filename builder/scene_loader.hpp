// Scene loader: reads a scene file into a Scene (builder/scene.hpp) in world coordinates, one
// MeshInfo per mesh instance, each classified closed/open (docs/architecture.md §4) or declared a heightfield.
//
// Formats: everything assimp 5.2 imports, chosen by file extension: OBJ, PLY (ascii and binary),
// glTF 2.0 (.gltf, .glb), FBX, Collada (.dae), IFC, STL, OFF, 3DS, ...; Terragen (.ter) by our own reader.
// Only triangles are kept (polygons are triangulated; points and lines are ignored).
// Node transforms are composed and applied in double here rather than by assimp's
// aiProcess_PreTransformVertices, for two reasons: every mesh instance keeps its node name (for
// heightfield matching and the log; PreTransformVertices merges meshes by material and drops the
// hierarchy), and composition adds no rounding (assimp stores each matrix and vertex in float, so
// values are float-rounded once when parsed, but a vertex at 0.3 under a node at 10^7 stays
// 10000000.3 instead of snapping to float's 1-unit grid there). Mirroring transforms (negative
// determinant) swap the winding so front faces stay front faces.
// Coordinates are not converted: the file's own axes and units are kept, except where assimp's
// importer itself converts (its IFC importer turns IFC's z-up into y-up through the root node).
// Terragen .ter is read by our own reader (assimp 5.2's is broken: assimp issues #3093, #4931):
// z up, x east, y north, metres (x, y = sample index * SCAL, z = SCAL.z * (base + sample * scale /
// 65536)), origin at the south-west sample, two triangles per cell counter-clockwise seen from above,
// one mesh named after the file stem. RealisticTerrain.ter: 257 x 257 samples at 30 m, 131,072
// triangles, bounds [0, 0, -79.0] .. [7680, 7680, 874.5], identical to scenes/terragen's .ply.
// Declare it a heightfield (LoadOptions::heightfield_meshes = {"RealisticTerrain"} or {"*"}).
// Mesh names: "<node>/<mesh>" (or just one of them when the other is empty or equal), the file stem
// when both are empty (PLY, STL); repeats get "#2", "#3"... A heightfield entry matches a mesh instance by
// its full name, its node name or its mesh name; "*" matches all.
//
// Errors: not_found when the file does not exist; unsupported when no importer handles its
// extension (the format is chosen by extension only); io_error when it cannot be read;
// invalid_input when assimp (or the .ter reader) fails (the message carries the file name and assimp's
// message, which often names the line), when nothing but points/lines/degenerate triangles remain ("no
// triangles"), when a heightfield name matches no mesh (the message lists the meshes), or when the
// scene exceeds 2^32 - 1 vertices or triangles.
// Logging: spdlog info per scene (triangles, dropped, bounds, seconds, classification summary),
// debug per mesh. assimp's own log goes to spdlog at debug level (a process-wide assimp logger is
// installed on first use).
// Thread safety: load_scene may run concurrently on different files (one assimp Importer each).
// Untrusted input: meant to be safe (no crash, no hang, errors returned), but assimp's parsers are
// the weak point. Done here: assimp exceptions and bad_alloc are caught, assimp's data-structure
// validation runs, every index is checked; PLY and OFF files are checked against what their headers
// declare before assimp sees them (builder/mesh_file_prechecks.hpp: headers that hang assimp 5.2,
// element and list counts that would make it allocate gigabytes); .ter is parsed by our own
// bounds-checked reader.
// Known left: assimp's PLY importer leaks its parse tree when a binary file ends early (bounded by
// the file size), and formats not listed above may still make assimp use much memory or time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "builder/scene.hpp"
#include "builder/nearly_closed_meshes.hpp"
#include "codec/light_frame.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct LoadOptions {
  // Meshes that are solid below (terrain): names as above, or "*" for all. Each must match a mesh.
  std::vector<std::string> heightfield_meshes;
  // The scene's up axis. Informational: the loader does not rotate anything; it is logged and used
  // by callers to turn sun azimuth/elevation into a light direction.
  UpAxis up = UpAxis::z;
  // Accept nearly closed meshes as solids (builder/nearly_closed_meshes.hpp: the winding-number test,
  // patches over their holes). Only meaningful under the `anywhere` contract; the build records it.
  bool close_nearly_closed = false;
  NearlyClosedOptions nearly_closed = {};
};

struct LoadStats {
  uint64_t triangles = 0;          // kept, = Scene::triangle_count()
  uint64_t dropped_triangles = 0;  // degenerate, non-finite or malformed (see Scene::add_mesh)
  uint64_t meshes = 0;             // mesh instances, = Scene::meshes.size()
  uint64_t closed_meshes = 0;
  uint64_t open_meshes = 0;
  uint64_t heightfield_meshes = 0;
  NearlyClosedReport nearly_closed;  // when LoadOptions::close_nearly_closed
  double seconds = 0;  // wall time of the whole load
};

// Loads `file`. `stats`, when given, is filled on success (and left untouched on error).
Result<Scene> load_scene(const std::filesystem::path& file, const LoadOptions& options,
                         LoadStats* stats = nullptr);

}  // namespace shadowtiles
