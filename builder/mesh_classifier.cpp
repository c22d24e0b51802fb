#include "builder/mesh_classifier.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>

namespace shadowtiles {
namespace {

constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();

uint64_t mix(uint64_t x) {  // splitmix64 finaliser: cheap, good avalanche for bit patterns
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

uint64_t bits(double value) {
  if (value == 0.0) value = 0.0;  // -0.0 and +0.0 are the same position
  uint64_t b;
  std::memcpy(&b, &value, sizeof b);
  return b;
}

// Power of two >= 2 * n: open addressing stays under half full, so probes stay short.
size_t table_size(size_t n) { return std::bit_ceil(std::max<size_t>(16, n * 2)); }

}  // namespace

std::vector<uint32_t> weld_positions(std::span<const Vec3> vertices, uint32_t* unique_count) {
  std::vector<uint32_t> weld(vertices.size());
  // Flat open-addressing set of representative vertex indices; positions compared by bit pattern.
  const size_t mask = table_size(vertices.size()) - 1;
  std::vector<uint32_t> slots(mask + 1, kEmpty);
  std::vector<uint32_t> dense_id;  // representative vertex -> dense id
  dense_id.reserve(vertices.size());
  std::vector<uint32_t> id_of(vertices.size(), kEmpty);
  uint32_t next_id = 0;
  for (size_t i = 0; i < vertices.size(); ++i) {
    const uint64_t bx = bits(vertices[i][0]), by = bits(vertices[i][1]), bz = bits(vertices[i][2]);
    size_t slot = mix(bx ^ mix(by ^ mix(bz))) & mask;
    while (true) {
      const uint32_t rep = slots[slot];
      if (rep == kEmpty) {
        slots[slot] = uint32_t(i);
        id_of[i] = next_id++;
        weld[i] = id_of[i];
        break;
      }
      const Vec3& r = vertices[rep];
      if (bits(r[0]) == bx && bits(r[1]) == by && bits(r[2]) == bz) {
        weld[i] = id_of[rep];
        break;
      }
      slot = (slot + 1) & mask;
    }
  }
  if (unique_count) *unique_count = next_id;
  return weld;
}

MeshClassification classify_welded_triangles(std::span<const std::array<uint32_t, 3>> triangles,
                                             uint32_t vertex_count) {
  MeshClassification result;
  // Undirected edge (a < b) -> uses in direction a->b and b->a. Flat open addressing keyed by a<<32|b;
  // a < b means the all-ones key never occurs, so it marks empty slots.
  struct Slot {
    uint64_t key = std::numeric_limits<uint64_t>::max();
    uint32_t forward = 0;
    uint32_t backward = 0;
  };
  const size_t mask = table_size(triangles.size() * 3 / 2 + 1) - 1;
  std::vector<Slot> table(mask + 1);
  uint64_t used_triangles = 0;
  for (const auto& t : triangles) {
    if (t[0] >= vertex_count || t[1] >= vertex_count || t[2] >= vertex_count || t[0] == t[1] ||
        t[1] == t[2] || t[0] == t[2]) {
      ++result.skipped_triangles;
      continue;
    }
    ++used_triangles;
    for (int k = 0; k < 3; ++k) {
      const uint32_t from = t[k], to = t[(k + 1) % 3];
      const bool forward = from < to;
      const uint64_t key = forward ? (uint64_t(from) << 32 | to) : (uint64_t(to) << 32 | from);
      size_t slot = mix(key) & mask;
      while (table[slot].key != key && table[slot].key != std::numeric_limits<uint64_t>::max())
        slot = (slot + 1) & mask;
      Slot& s = table[slot];
      if (s.key != key) {
        s.key = key;
        ++result.edges;
      }
      ++(forward ? s.forward : s.backward);
    }
  }
  for (const Slot& s : table) {
    if (s.key == std::numeric_limits<uint64_t>::max()) continue;
    const uint64_t uses = uint64_t(s.forward) + s.backward;
    if (uses == 1)
      ++result.boundary_edges;
    else if (uses > 2)
      ++result.non_manifold_edges;
    else if (s.forward != 1)  // two uses, same direction: neighbours disagree on orientation
      ++result.misoriented_edges;
  }
  const bool closed = used_triangles > 0 && result.skipped_triangles == 0 && result.boundary_edges == 0 &&
                      result.non_manifold_edges == 0 && result.misoriented_edges == 0;
  result.kind = closed ? MeshKind::closed : MeshKind::open;
  return result;
}

MeshClassification classify_mesh(std::span<const Vec3> vertices,
                                 std::span<const std::array<uint32_t, 3>> triangles) {
  uint32_t unique = 0;
  const std::vector<uint32_t> weld = weld_positions(vertices, &unique);
  std::vector<std::array<uint32_t, 3>> welded;
  welded.reserve(triangles.size());
  uint64_t out_of_range = 0;
  for (const auto& t : triangles) {
    if (t[0] >= vertices.size() || t[1] >= vertices.size() || t[2] >= vertices.size()) {
      ++out_of_range;
      continue;
    }
    welded.push_back({weld[t[0]], weld[t[1]], weld[t[2]]});
  }
  MeshClassification result = classify_welded_triangles(welded, unique);
  result.skipped_triangles += out_of_range;
  if (out_of_range > 0) result.kind = MeshKind::open;
  result.signed_volume = mesh_signed_volume(vertices, triangles);
  return result;
}

double mesh_signed_volume(std::span<const Vec3> vertices,
                          std::span<const std::array<uint32_t, 3>> triangles) {
  if (vertices.empty()) return 0;
  // Tetrahedra against the first vertex rather than the origin: the same volume for a closed mesh,
  // without cancellation when the mesh sits far from the origin.
  const Vec3& o = vertices[0];
  double six_volume = 0;
  for (const auto& t : triangles) {
    if (t[0] >= vertices.size() || t[1] >= vertices.size() || t[2] >= vertices.size()) continue;
    const Vec3& p = vertices[t[0]];
    const Vec3& q = vertices[t[1]];
    const Vec3& r = vertices[t[2]];
    const double ax = p[0] - o[0], ay = p[1] - o[1], az = p[2] - o[2];
    const double bx = q[0] - o[0], by = q[1] - o[1], bz = q[2] - o[2];
    const double cx = r[0] - o[0], cy = r[1] - o[1], cz = r[2] - o[2];
    six_volume += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
  }
  return six_volume / 6.0;
}

}  // namespace shadowtiles
