#include "builder/mesh_classifier.hpp"

#include <algorithm>
#include <array>
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

// Sorts `keys` (each below 2^bits) by 8-bit digits, least significant first; `scratch`: working space.
// A digit every key shares is skipped.
void sort_keys(std::vector<uint64_t>& keys, std::vector<uint64_t>& scratch, unsigned bits) {
  scratch.resize(keys.size());
  for (unsigned shift = 0; shift < bits; shift += 8) {
    std::array<size_t, 257> count{};
    for (const uint64_t k : keys) ++count[((k >> shift) & 0xff) + 1];
    if (std::find(count.begin() + 1, count.end(), keys.size()) != count.end()) continue;
    for (size_t d = 1; d < count.size(); ++d) count[d] += count[d - 1];
    for (const uint64_t k : keys) scratch[count[(k >> shift) & 0xff]++] = k;
    keys.swap(scratch);
  }
}

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
  // Each use of an undirected edge (a < b) as the key a << bits | b, in one list per direction;
  // sorted, a run of equal keys is one edge's uses. Sorting by digits reads and writes the lists in
  // order, where a hash table of the edges was one cache miss (and on this VM a page fault per 4 kB
  // of a 16 MB table) per use: dragon's 202,520 triangles took 70-85 ms that way.
  const unsigned bits = unsigned(std::bit_width(vertex_count));  // ids < vertex_count < 2^bits; 2 * bits <= 64
  std::vector<uint64_t> forward, backward;  // uses a -> b and b -> a
  forward.reserve(triangles.size() * 3 / 2 + 1);
  backward.reserve(triangles.size() * 3 / 2 + 1);
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
      if (from < to)
        forward.push_back(uint64_t(from) << bits | to);
      else
        backward.push_back(uint64_t(to) << bits | from);
    }
  }
  std::vector<uint64_t> scratch;
  sort_keys(forward, scratch, 2 * bits);
  sort_keys(backward, scratch, 2 * bits);
  // Merge the two sorted lists edge by edge.
  size_t f = 0, b = 0;
  while (f < forward.size() || b < backward.size()) {
    const uint64_t key = b == backward.size() || (f < forward.size() && forward[f] < backward[b]) ? forward[f]
                                                                                                  : backward[b];
    uint64_t forward_uses = 0, backward_uses = 0;
    for (; f < forward.size() && forward[f] == key; ++f) ++forward_uses;
    for (; b < backward.size() && backward[b] == key; ++b) ++backward_uses;
    ++result.edges;
    const uint64_t uses = forward_uses + backward_uses;
    if (uses == 1)
      ++result.boundary_edges;
    else if (uses > 2)
      ++result.non_manifold_edges;
    else if (forward_uses != 1)  // two uses, same direction: neighbours disagree on orientation
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
