// Reads the most common PLY layout, a binary little-endian triangle mesh, without assimp: scanned and
// city meshes (oahu, honolulu) come this way, and assimp 5.2 builds a property-by-property document
// of the whole file first (0.10-0.12 s and ~6x the file in memory for a 9 MB file; this reader:
// two sequential reads, the mesh's own arrays).
//
// Accepted (anything else returns nullopt and the caller imports the file with assimp as before):
// - "format binary_little_endian 1.0" on the line after "ply", comments only before the first
//   element, then an element "vertex" and an element "face", no others; header lines end in \n or
//   \r\n; the body's first byte is no line end;
// - the vertex element's properties are scalars, with x, y and z of type float (float32) once each;
// - the face element has one property, a list named vertex_indices (or vertex_index) of 4-byte
//   integer indices, with an integer count type;
// - every face has 3 indices, each naming a vertex (a polygon, a negative or out-of-range index
//   sends the file to assimp, which triangulates or reports it).
// The result is what assimp gives for such a file: the vertices and triangles in file order, no
// names, no transform.
//
// Precondition: check_ply_file has accepted the file (so the header is text, ends, and the body
// holds what it declares).
// Errors: io_error when the file cannot be read.
// Thread safety: a pure function of the file.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles {

struct PlyTriangleMesh {
  std::vector<std::array<float, 3>> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
};

Result<std::optional<PlyTriangleMesh>> read_ply_triangles(const std::filesystem::path& file, uint64_t file_size);

}  // namespace shadowtiles
