#include "builder/ply_triangle_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>

#include "builder/ply_scalar_types.hpp"

namespace shadowtiles {
namespace {

// Header words split on spaces and tabs (as assimp splits them); a trailing \r is dropped. A line with
// any other \r gives no words (the caller then leaves the file to assimp).
std::vector<std::string_view> words_of(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  std::vector<std::string_view> words;
  if (line.find('\r') != std::string_view::npos) return words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

// The layout the reader takes; see the header.
struct Layout {
  uint64_t vertices = 0, faces = 0;
  uint64_t body_offset = 0;
  unsigned vertex_bytes = 0;             // one vertex record
  std::array<unsigned, 3> xyz_offset{};  // within it
  unsigned count_bytes = 0;              // a face's list count
};

bool parse_layout(std::string_view head, Layout& layout) {
  std::array<bool, 3> have_xyz{};
  int element = -1;  // 0 vertex, 1 face
  bool face_list = false;
  size_t pos = 0;
  for (unsigned line_number = 0;; ++line_number) {
    const size_t end = head.find('\n', pos);
    if (end == std::string_view::npos) return false;
    const auto words = words_of(head.substr(pos, end - pos));
    pos = end + 1;
    if (line_number == 0) {
      if (words.size() != 1 || words[0] != "ply") return false;
      continue;
    }
    if (line_number == 1) {  // assimp wants the format right after the magic line
      if (words.size() != 3 || words[0] != "format" || words[1] != "binary_little_endian" || words[2] != "1.0")
        return false;
      continue;
    }
    // Comments only before the first element: assimp ends an element's properties at any other line
    // (a comment, a blank line), dropping the properties after it.
    if (element == -1 && !words.empty() && (words[0] == "comment" || words[0] == "obj_info")) continue;
    if (words.empty()) return false;
    if (words[0] == "element") {
      if (words.size() != 3) return false;
      uint64_t count = 0;
      for (char c : words[2]) {
        if (c < '0' || c > '9' || count > (uint64_t(1) << 40)) return false;
        count = count * 10 + uint64_t(c - '0');
      }
      if (element == -1 && words[1] == "vertex") {
        element = 0;
        layout.vertices = count;
      } else if (element == 0 && words[1] == "face") {
        element = 1;
        layout.faces = count;
      } else {
        return false;  // another element, or out of order: assimp's
      }
    } else if (words[0] == "property") {
      if (element == 0) {
        if (words.size() != 3) return false;  // lists in vertices: assimp's
        const unsigned bytes = ply_type(words[1]).bytes;
        if (bytes == 0) return false;
        static constexpr std::string_view kAxes[3] = {"x", "y", "z"};
        for (int k = 0; k < 3; ++k)
          if (words[2] == kAxes[k]) {
            if (have_xyz[k] || (words[1] != "float" && words[1] != "float32")) return false;
            have_xyz[k] = true;
            layout.xyz_offset[k] = layout.vertex_bytes;
          }
        layout.vertex_bytes += bytes;
      } else if (element == 1) {
        if (face_list || words.size() != 5 || words[1] != "list") return false;
        if (words[4] != "vertex_indices" && words[4] != "vertex_index") return false;
        const PlyScalarType count = ply_type(words[2]), index = ply_type(words[3]);
        layout.count_bytes = count.bytes;
        if (count.bytes == 0 || !count.is_integer || index.bytes != 4 || !index.is_integer) return false;
        face_list = true;
      } else {
        return false;
      }
    } else if (words[0] == "end_header") {
      layout.body_offset = pos;
      // A body starting with a line-end byte: assimp's text reader may take it as the header's line end.
      if (pos < head.size() && (head[pos] == '\n' || head[pos] == '\r')) return false;
      return element == 1 && face_list && have_xyz[0] && have_xyz[1] && have_xyz[2] && layout.faces > 0 &&
             layout.vertices <= 0xffffffffull && layout.faces <= 0xffffffffull;
    } else {
      return false;
    }
  }
}

// Little-endian integer of `bytes` (1, 2 or 4) bytes.
uint32_t load_le(const unsigned char* p, unsigned bytes) {
  uint32_t v = 0;
  for (unsigned i = bytes; i-- > 0;) v = (v << 8) | p[i];
  return v;
}

}  // namespace

Result<std::optional<PlyTriangleMesh>> read_ply_triangles(const std::filesystem::path& file, uint64_t file_size) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return make_error(ErrorCode::io_error, fmt::format("{}: cannot open", file.string()));
  std::string head(size_t(std::min<uint64_t>(file_size, 1 << 16)), '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(size_t(std::max<std::streamsize>(0, in.gcount())));
  Layout layout;
  if (!parse_layout(head, layout)) return std::optional<PlyTriangleMesh>();
  const uint64_t face_bytes = layout.count_bytes + 12;
  const uint64_t body = file_size - std::min(file_size, layout.body_offset);
  if (layout.vertices * layout.vertex_bytes + layout.faces * face_bytes > body) return std::optional<PlyTriangleMesh>();

  PlyTriangleMesh mesh;
  mesh.vertices.resize(size_t(layout.vertices));
  mesh.triangles.resize(size_t(layout.faces));
  in.clear();
  in.seekg(std::streamoff(layout.body_offset));
  // Records in blocks of about 1 MiB: two sequential reads, no copy of the whole body.
  std::vector<unsigned char> block;
  auto read_records = [&](uint64_t count, uint64_t record_bytes, auto&& take) {
    const uint64_t per_block = std::max<uint64_t>(1, (1 << 20) / record_bytes);
    for (uint64_t first = 0; first < count; first += per_block) {
      const uint64_t n = std::min(per_block, count - first);
      block.resize(size_t(n * record_bytes));
      in.read(reinterpret_cast<char*>(block.data()), std::streamsize(block.size()));
      if (uint64_t(in.gcount()) != block.size()) return false;
      for (uint64_t i = 0; i < n; ++i)
        if (!take(first + i, block.data() + i * record_bytes)) return false;
    }
    return true;
  };
  if (!read_records(layout.vertices, layout.vertex_bytes, [&](uint64_t i, const unsigned char* record) {
        for (int k = 0; k < 3; ++k) std::memcpy(&mesh.vertices[i][k], record + layout.xyz_offset[k], 4);
        return true;
      }))
    return make_error(ErrorCode::io_error, fmt::format("{}: PLY: the body could not be read", file.string()));
  bool triangles_only = true;
  if (!read_records(layout.faces, face_bytes, [&](uint64_t i, const unsigned char* record) {
        if (load_le(record, layout.count_bytes) != 3) return triangles_only = false;
        for (int k = 0; k < 3; ++k) {
          const uint32_t index = load_le(record + layout.count_bytes + 4 * k, 4);
          if (index >= layout.vertices) return triangles_only = false;  // negative ints land here too
          mesh.triangles[i][k] = index;
        }
        return true;
      })) {
    if (!triangles_only) return std::optional<PlyTriangleMesh>();  // polygons or bad indices: assimp's
    return make_error(ErrorCode::io_error, fmt::format("{}: PLY: the body could not be read", file.string()));
  }
  return std::optional<PlyTriangleMesh>(std::move(mesh));
}

}  // namespace shadowtiles
