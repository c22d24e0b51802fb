#include "builder/winding_number_tree.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "codec/vec3_math.hpp"

namespace shadowtiles {
namespace {

constexpr uint32_t kLeafTriangles = 8;

// Net uses of undirected edges, sorted by key (a << 32 | b, a < b): forward a->b minus backward.
using Boundary = std::vector<std::pair<uint64_t, int64_t>>;

void sort_and_cancel(Boundary& edges) {
  std::sort(edges.begin(), edges.end());
  size_t out = 0;
  for (size_t i = 0; i < edges.size();) {
    int64_t net = 0;
    size_t j = i;
    for (; j < edges.size() && edges[j].first == edges[i].first; ++j) net += edges[j].second;
    if (net != 0) edges[out++] = {edges[i].first, net};
    i = j;
  }
  edges.resize(out);
}

Boundary merge(const Boundary& a, const Boundary& b) {
  Boundary out;
  out.reserve(a.size() + b.size());
  size_t i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && a[i].first < b[j].first)) {
      out.push_back(a[i++]);
    } else if (i == a.size() || b[j].first < a[i].first) {
      out.push_back(b[j++]);
    } else {
      const int64_t net = a[i].second + b[j].second;
      if (net != 0) out.push_back({a[i].first, net});
      ++i, ++j;
    }
  }
  return out;
}

}  // namespace

double triangle_winding(const Vec3& pa, const Vec3& pb, const Vec3& pc, const Vec3& p) {
  const Vec3 a = sub(pa, p), b = sub(pb, p), c = sub(pc, p);
  const double la = norm(a), lb = norm(b), lc = norm(c);
  const double det = dot(a, cross(b, c));
  const double denominator = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
  return std::atan2(det, denominator) / (2 * std::numbers::pi);
}

WindingNumberTree::WindingNumberTree(const std::vector<Vec3>& vertices,
                                     std::span<const std::array<uint32_t, 3>> triangles)
    : vertices_(vertices), triangles_(triangles.begin(), triangles.end()) {
  if (triangles_.empty()) return;
  nodes_.reserve(2 * (triangles_.size() / kLeafTriangles + 1));
  Boundary boundary;
  build(0, uint32_t(triangles_.size()), boundary);
}

uint32_t WindingNumberTree::build(uint32_t first, uint32_t count, Boundary& boundary) {
  const uint32_t index = uint32_t(nodes_.size());
  nodes_.push_back({});
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  Vec3 centroid_lo = lo, centroid_hi = hi;
  for (uint32_t t = first; t < first + count; ++t) {
    Vec3 centroid{0, 0, 0};
    for (uint32_t v : triangles_[t])
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], vertices_[v][k]);
        hi[k] = std::max(hi[k], vertices_[v][k]);
        centroid[k] += vertices_[v][k] / 3;
      }
    for (int k = 0; k < 3; ++k) {
      centroid_lo[k] = std::min(centroid_lo[k], centroid[k]);
      centroid_hi[k] = std::max(centroid_hi[k], centroid[k]);
    }
  }
  uint32_t left = 0, right = 0;
  if (count <= kLeafTriangles) {
    boundary.clear();
    for (uint32_t t = first; t < first + count; ++t)
      for (int k = 0; k < 3; ++k) {
        const uint32_t from = triangles_[t][k], to = triangles_[t][(k + 1) % 3];
        if (from < to) boundary.push_back({uint64_t(from) << 32 | to, 1});
        else if (to < from) boundary.push_back({uint64_t(to) << 32 | from, -1});
      }
    sort_and_cancel(boundary);
  } else {
    // Median split of the centroids along their widest axis.
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (centroid_hi[k] - centroid_lo[k] > centroid_hi[axis] - centroid_lo[axis]) axis = k;
    auto centre_of = [&](const std::array<uint32_t, 3>& t) {
      return vertices_[t[0]][axis] + vertices_[t[1]][axis] + vertices_[t[2]][axis];
    };
    const uint32_t half = count / 2;
    std::nth_element(triangles_.begin() + first, triangles_.begin() + first + half, triangles_.begin() + first + count,
                     [&](const auto& a, const auto& b) { return centre_of(a) < centre_of(b); });
    Boundary left_boundary, right_boundary;
    left = build(first, half, left_boundary);
    right = build(first + half, count - half, right_boundary);
    boundary = merge(left_boundary, right_boundary);
  }
  Node& node = nodes_[index];
  node.lo = lo;
  node.hi = hi;
  for (int k = 0; k < 3; ++k) node.centre[k] = 0.5 * (lo[k] + hi[k]);
  node.first = first;
  node.count = count;
  node.left = left;
  node.right = right;
  node.edge_first = uint32_t(edges_.size());
  // The cone pays when it has fewer triangles than the node; at most half as many keeps the stored
  // edges within half the triangles per tree level on any input (a soup of strips included).
  if (2 * boundary.size() < count) {
    for (const auto& [key, net] : boundary) {
      const uint32_t a = uint32_t(key >> 32), b = uint32_t(key);
      if (net > 0) edges_.push_back({a, b, int32_t(net)});
      else edges_.push_back({b, a, int32_t(-net)});
    }
    node.edge_count = uint32_t(boundary.size());
  } else {
    node.edge_count = count;  // marks "no cone" (edge_count >= count)
  }
  return index;
}

double WindingNumberTree::operator()(const Vec3& p) const {
  return nodes_.empty() ? 0.0 : evaluate(0, p);
}

double WindingNumberTree::evaluate(uint32_t index, const Vec3& p) const {
  const Node& node = nodes_[index];
  if (node.edge_count < node.count) {
    // Outside the box by a margin that rounding cannot cross: the closed S - C leaves p at 0.
    bool outside = false;
    for (int k = 0; k < 3 && !outside; ++k) {
      const double margin = 1e-9 * (std::fabs(node.lo[k]) + std::fabs(node.hi[k]) + 1.0);
      outside = p[k] < node.lo[k] - margin || p[k] > node.hi[k] + margin;
    }
    if (outside) {
      double w = 0;
      for (uint32_t e = node.edge_first; e < node.edge_first + node.edge_count; ++e)
        w += edges_[e].uses * triangle_winding(node.centre, vertices_[edges_[e].from], vertices_[edges_[e].to], p);
      return w;
    }
  }
  if (node.left == 0) {
    double w = 0;
    for (uint32_t t = node.first; t < node.first + node.count; ++t)
      w += triangle_winding(vertices_[triangles_[t][0]], vertices_[triangles_[t][1]], vertices_[triangles_[t][2]], p);
    return w;
  }
  return evaluate(node.left, p) + evaluate(node.right, p);
}

}  // namespace shadowtiles
