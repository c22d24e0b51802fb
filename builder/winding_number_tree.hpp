// The generalized winding number of one triangle set at many points, exactly (up to rounding), by
// the hierarchical evaluation of Jacobson et al. 2013 (section 3.3; libigl's WindingNumberTree):
// a bounding-volume tree over the triangles keeps, per node, the boundary of the node's triangles
// (directed edges with their net use). For a point outside a node's box, the node's triangles S and
// the cone C from the box centre over that boundary close each other (S - C has no boundary and lies
// inside the box), so w(S) = w(C): one solid angle per boundary edge instead of one per triangle.
// Near the point the tree is descended to its leaves, which are summed triangle by triangle.
// On a large nearly closed scan the boundaries are short against the triangle counts: the nearly
// closed test's whole winding numbers (builder/nearly_closed_meshes.cpp) cost a fraction of the
// brute-force sum (docs/receiver-contracts.md).
// Thread safety: construct once, then evaluate from any number of threads.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "codec/light_frame.hpp"

namespace shadowtiles {

// Signed solid angle of triangle (a, b, c) seen from p, over 4 pi (Van Oosterom and Strackee 1983):
// positive when p is on the side the counter-clockwise normal points away from.
double triangle_winding(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p);

class WindingNumberTree {
 public:
  // `vertices` must outlive the tree; triangles are copied (reordered by the tree).
  WindingNumberTree(const std::vector<Vec3>& vertices, std::span<const std::array<uint32_t, 3>> triangles);

  // Sum of the triangles' signed solid angles at p over 4 pi, as winding_number() of all of them.
  double operator()(const Vec3& p) const;

  size_t node_count() const { return nodes_.size(); }

 private:
  struct DirectedEdge {
    uint32_t from, to;
    int32_t uses;  // net uses in this direction (> 0)
  };
  struct Node {
    Vec3 lo{}, hi{};        // box of the node's triangles' vertices
    Vec3 centre{};          // the cone's apex
    uint32_t first = 0;     // triangles_[first, first + count)
    uint32_t count = 0;
    uint32_t edge_first = 0;  // edges_[edge_first, edge_first + edge_count): the node's boundary
    uint32_t edge_count = 0;
    uint32_t left = 0, right = 0;  // children (0: a leaf; the root is node 0, never a child)
  };

  uint32_t build(uint32_t first, uint32_t count, std::vector<std::pair<uint64_t, int64_t>>& boundary);
  double evaluate(uint32_t node, const Vec3& p) const;

  const std::vector<Vec3>& vertices_;
  std::vector<std::array<uint32_t, 3>> triangles_;
  std::vector<Node> nodes_;
  std::vector<DirectedEdge> edges_;
};

}  // namespace shadowtiles
