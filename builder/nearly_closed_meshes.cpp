#include "builder/nearly_closed_meshes.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "builder/mesh_classifier.hpp"
#include "builder/winding_number_tree.hpp"
#include "codec/vec3_math.hpp"
#include "common/parallel_for.hpp"

namespace shadowtiles {
namespace {

// Net uses of each undirected edge: key a<<32|b (a < b) -> forward (a->b) minus backward uses.
std::unordered_map<uint64_t, int64_t> net_edges(std::span<const std::array<uint32_t, 3>> triangles) {
  std::unordered_map<uint64_t, int64_t> net;
  net.reserve(triangles.size() * 2);
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t from = t[k], to = t[(k + 1) % 3];
      if (from < to) ++net[uint64_t(from) << 32 | to];
      else --net[uint64_t(to) << 32 | from];
    }
  return net;
}

}  // namespace

double winding_number(const std::vector<Vec3>& vertices, std::span<const std::array<uint32_t, 3>> triangles,
                      const Vec3& p) {
  double w = 0;
  for (const auto& t : triangles) w += triangle_winding(vertices[t[0]], vertices[t[1]], vertices[t[2]], p);
  return w;
}

MeshPatch patch_boundary_loops(std::vector<Vec3>& vertices, std::span<const std::array<uint32_t, 3>> triangles) {
  // The boundary chain as directed edges (with multiplicity), grouped by their start vertex.
  std::unordered_map<uint32_t, std::vector<uint32_t>> outgoing;
  std::vector<std::pair<uint64_t, int64_t>> edges;
  for (const auto& [key, count] : net_edges(triangles))
    if (count != 0) edges.emplace_back(key, count);
  std::sort(edges.begin(), edges.end());  // deterministic loops, whatever the hash order
  for (const auto& [key, count] : edges) {
    const uint32_t a = uint32_t(key >> 32), b = uint32_t(key & 0xffffffffu);
    for (int64_t k = 0; k < std::abs(count); ++k) {
      if (count > 0) outgoing[a].push_back(b);
      else outgoing[b].push_back(a);
    }
  }
  for (auto& [from, to] : outgoing) std::sort(to.begin(), to.end(), std::greater<>());  // popped smallest first

  MeshPatch patch;
  auto close_loop = [&](const std::vector<uint32_t>& loop) {  // loop[i] -> loop[i + 1], last -> first
    ++patch.loops;
    const size_t n = loop.size();
    if (n == 3) {  // a triangular hole: the reversed triangle, no centroid needed
      patch.triangles.push_back({loop[0], loop[2], loop[1]});
      return;
    }
    Vec3 centre{0, 0, 0};
    for (uint32_t v : loop)
      for (int k = 0; k < 3; ++k) centre[k] += vertices[v][k] / double(n);
    const uint32_t c = uint32_t(vertices.size());
    vertices.push_back(centre);
    // (c, next, this): the fan's boundary is the loop reversed, so mesh + fan has no boundary there.
    for (size_t i = 0; i < n; ++i) patch.triangles.push_back({c, loop[(i + 1) % n], loop[i]});
  };
  // Walk unused edges; every vertex has as many boundary edges in as out, so a walk only stops where it
  // started. A vertex met twice closes the simple loop between its two visits (fans over simple loops
  // hug the hole better than over figure-eights at non-manifold vertices).
  std::vector<uint32_t> starts;
  for (const auto& [from, to] : outgoing) starts.push_back(from);
  std::sort(starts.begin(), starts.end());
  std::unordered_map<uint32_t, size_t> on_path;
  for (uint32_t start : starts) {
    while (!outgoing[start].empty()) {
      std::vector<uint32_t> path{start};
      on_path.clear();
      on_path[start] = 0;
      uint32_t at = start;
      while (true) {
        auto& out = outgoing[at];
        if (out.empty()) break;  // only at the start, where the walk is closed
        const uint32_t next = out.back();
        out.pop_back();
        if (auto seen = on_path.find(next); seen != on_path.end()) {
          std::vector<uint32_t> loop(path.begin() + ptrdiff_t(seen->second), path.end());
          for (size_t k = seen->second + 1; k < path.size(); ++k) on_path.erase(path[k]);
          path.resize(seen->second + 1);
          close_loop(loop);
          at = next;
          continue;
        }
        on_path[next] = path.size();
        path.push_back(next);
        at = next;
      }
    }
  }
  return patch;
}

NearlyClosedReport close_nearly_closed_meshes(Scene& scene, const NearlyClosedOptions& options) {
  NearlyClosedReport report;
  scene.nearly_closed_tested = true;
  const uint32_t mesh_count = uint32_t(scene.meshes.size());
  for (uint32_t m = 0; m < mesh_count; ++m) {
    MeshInfo& info = scene.meshes[m];
    if (info.kind != MeshKind::open || info.triangle_count == 0) continue;
    MeshClosingReport r;
    r.mesh = m;
    r.boundary_edges = info.boundary_edges;
    r.non_manifold_edges = info.non_manifold_edges;
    r.misoriented_edges = info.misoriented_edges;
    const std::span<const std::array<uint32_t, 3>> triangles(scene.triangles.data() + info.first_triangle,
                                                             info.triangle_count);
    const size_t vertex_count = scene.vertices.size();
    MeshPatch patch = patch_boundary_loops(scene.vertices, triangles);
    r.loops = patch.loops;
    r.patch_triangles = uint32_t(patch.triangles.size());
    auto refuse = [&](std::string why) {
      r.reason = std::move(why);
      scene.vertices.resize(vertex_count);  // drop the centroids
    };
    if (patch.triangles.size() > options.max_patch_triangles) {
      refuse("boundary too long for the w test (" + std::to_string(patch.triangles.size()) + " patch triangles)");
    } else {
      // Volume of mesh + patches (positive: outward-facing).
      std::vector<std::array<uint32_t, 3>> all(triangles.begin(), triangles.end());
      all.insert(all.end(), patch.triangles.begin(), patch.triangles.end());
      r.patched_volume = mesh_signed_volume(scene.vertices, all);
      // Samples: every triangle, or max_samples stratified by area (deterministic).
      std::vector<double> area(triangles.size());
      double total_area = 0;
      for (size_t i = 0; i < triangles.size(); ++i) {
        const auto& t = triangles[i];
        area[i] = 0.5 * norm(cross(sub(scene.vertices[t[1]], scene.vertices[t[0]]),
                                   sub(scene.vertices[t[2]], scene.vertices[t[0]])));
        total_area += area[i];
      }
      std::vector<std::pair<size_t, double>> samples;  // triangle, weight (share of the area)
      if (triangles.size() <= options.max_samples) {
        for (size_t i = 0; i < triangles.size(); ++i) samples.emplace_back(i, area[i] / total_area);
      } else {
        const double step = total_area / options.max_samples;
        double cumulative = 0, next = 0.5 * step;
        for (size_t i = 0; i < triangles.size() && samples.size() < options.max_samples; ++i) {
          cumulative += area[i];
          while (cumulative > next && samples.size() < options.max_samples) {
            samples.emplace_back(i, 1.0 / options.max_samples);
            next += step;
          }
        }
      }
      r.samples = uint32_t(samples.size());
      // The whole winding number (mesh + patches) on a subset of the samples, within a budget of solid
      // angles: 0 just outside, 1 just inside, or the surface there is inside its own solid (faces
      // between touching parts, parts overlapping) or inverted (a flipped face).
      const size_t full_count = std::min(samples.size(), std::max<size_t>(options.min_full_samples,
                                                                          options.full_budget / triangles.size()));
      const double full_stride = double(samples.size()) / double(full_count);
      size_t next_full = 0;
      // The points whose whole winding number is wanted: w_patch now, the mesh's part below, in parallel.
      struct FullPoint {
        size_t sample;
        bool outside;
        Vec3 p;
        double w_patch;
      };
      std::vector<FullPoint> full_points;
      // The patch's part at both points of every sample: a tree too (a long boundary's patch has up
      // to max_patch_triangles triangles, x max_samples x 2 points).
      const WindingNumberTree patch_tree(scene.vertices, patch.triangles);
      // Both points of every sample and their w_patch, on every build thread; then, in sample order,
      // what they say (so the sums and the full points are the same for any thread count).
      std::vector<std::array<Vec3, 2>> points(samples.size());
      std::vector<std::array<double, 2>> w_patch(samples.size());
      parallel_for_ranges(options.threads, samples.size(), [&](size_t begin, size_t end) {
        for (size_t s = begin; s < end; ++s) {
          const auto& t = triangles[samples[s].first];
          const Vec3 &a = scene.vertices[t[0]], &b = scene.vertices[t[1]], &c = scene.vertices[t[2]];
          const Vec3 n = cross(sub(b, a), sub(c, a));
          const double length = norm(n);
          // Offset: a hundredth of the triangle's size, along the unit normal, both sides.
          const double eps = 0.01 * std::sqrt(0.5 * length);
          for (int side = 0; side < 2; ++side) {
            const double sign = side == 0 ? 1.0 : -1.0;
            Vec3& p = points[s][side];
            for (int k = 0; k < 3; ++k) p[k] = (a[k] + b[k] + c[k]) / 3 + sign * eps * n[k] / length;
            w_patch[s][side] = patch_tree(p);
          }
        }
      });
      for (size_t s = 0; s < samples.size(); ++s) {
        const bool full = next_full < full_count && s >= size_t(double(next_full) * full_stride);
        if (full) ++next_full;
        double deviation = 0;
        for (int side = 0; side < 2; ++side) {
          deviation = std::max(deviation, std::fabs(w_patch[s][side]));
          if (full) full_points.push_back({s, side == 0, points[s][side], w_patch[s][side]});
        }
        r.max_deviation = std::max(r.max_deviation, deviation);
        if (deviation > options.tolerance) r.ambiguous_area += samples[s].second;
      }
      // The mesh's part at every full point: hierarchically (winding_number_tree.hpp; the brute-force
      // sum of samples x triangles solid angles was most of a large scan's load time), on every build
      // thread.
      std::vector<double> w_mesh(full_points.size());
      const WindingNumberTree tree(scene.vertices, triangles);
      parallel_for_ranges(options.threads, full_points.size(), [&](size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) w_mesh[k] = tree(full_points[k].p);
      });
      double full_weight = 0, misplaced_weight = 0;
      for (size_t k = 0; k < full_points.size(); k += 2) {  // each full sample's outside, then inside point
        bool misplaced = false;
        for (size_t side = k; side < k + 2; ++side)
          misplaced |= std::lround(w_mesh[side] + full_points[side].w_patch) != (full_points[side].outside ? 0 : 1);
        const double weight = samples[full_points[k].sample].second;
        ++r.full_samples;
        r.misplaced_samples += misplaced;
        full_weight += weight;
        if (misplaced) misplaced_weight += weight;
      }
      r.misplaced_area = full_weight > 0 ? misplaced_weight / full_weight : 0;
      if (!(r.patched_volume > 0))
        refuse("mesh + patches has no positive volume (inside out or flat)");
      else if (r.misplaced_samples > 0 && r.misplaced_area > options.max_misplaced_area)
        refuse("its winding number is not 0 outside and 1 inside at " + std::to_string(r.misplaced_samples) +
               " of " + std::to_string(r.full_samples) + " samples (faces inside its own solid, or flipped), " +
               fmt::format("{:.2f}% of their area", 100 * r.misplaced_area));
      else if (r.ambiguous_area > options.max_ambiguous_area)
        refuse("winding number ambiguous on too much of the surface");
      else
        r.accepted = true;
    }
    if (r.accepted) {
      info.kind = MeshKind::closed;
      info.nearly_closed = true;
      info.signed_volume = r.patched_volume;
      for (const auto& t : patch.triangles) {
        scene.patch_triangles.push_back(t);
        scene.patch_mesh.push_back(m);
      }
      ++report.accepted_meshes;
      report.accepted_triangles += info.triangle_count;
      report.patch_triangles += patch.triangles.size();
    }
    spdlog::info("  mesh '{}': nearly closed {}: {} triangles, edges {} boundary {} non-manifold {} misoriented, "
                 "{} loops ({} patch triangles), w deviation |w_patch| over {} samples: max {:.3f}, {:.2f}% of the area "
                 "above the tolerance {} (at most {:.2f}%), w not 0 outside / 1 inside at {} of {} samples ({:.2f}% of "
                 "their area, at most {:.2f}%){}{}",
                 info.name, r.accepted ? "accepted" : "refused", info.triangle_count, r.boundary_edges,
                 r.non_manifold_edges, r.misoriented_edges, r.loops, r.patch_triangles, r.samples, r.max_deviation,
                 100 * r.ambiguous_area, options.tolerance, 100 * options.max_ambiguous_area, r.misplaced_samples,
                 r.full_samples, 100 * r.misplaced_area, 100 * options.max_misplaced_area, r.accepted ? "" : ": ",
                 r.reason);
    report.meshes.push_back(std::move(r));
  }
  spdlog::info("nearly closed meshes: {} of {} open meshes accepted as solids ({} triangles, {} patch triangles; "
               "tolerance {}, ambiguous area at most {:.2f}%)",
               report.accepted_meshes, report.meshes.size(), report.accepted_triangles, report.patch_triangles,
               options.tolerance, 100 * options.max_ambiguous_area);
  return report;
}

}  // namespace shadowtiles
