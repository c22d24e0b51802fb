#include "bench/harness/stability_scenes.hpp"

#include <array>
#include <fstream>
#include <vector>

namespace shadowtiles::bench {
namespace {

struct ObjWriter {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::pair<std::string, std::vector<std::array<int, 3>>>> objects;

  int vertex(double x, double y, double z) {
    vertices.push_back({x, y, z});
    return int(vertices.size());  // OBJ indices are 1-based
  }
  // Quad a b c d counter-clockwise seen from the side it faces.
  void quad(const std::string& name, std::array<double, 3> a, std::array<double, 3> b, std::array<double, 3> c,
            std::array<double, 3> d) {
    int ia = vertex(a[0], a[1], a[2]), ib = vertex(b[0], b[1], b[2]), ic = vertex(c[0], c[1], c[2]),
        id = vertex(d[0], d[1], d[2]);
    objects.push_back({name, {{ia, ib, ic}, {ia, ic, id}}});
  }
  // Closed axis-aligned box, outward faces counter-clockwise (shared corner vertices: watertight).
  void box(const std::string& name, std::array<double, 3> lo, std::array<double, 3> hi) {
    int v[8];
    for (int i = 0; i < 8; ++i)
      v[i] = vertex((i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]);
    const int faces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                              {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    std::vector<std::array<int, 3>> triangles;
    for (const auto& f : faces) triangles.push_back({v[f[0]], v[f[1]], v[f[2]]});
    objects.push_back({name, triangles});
  }
  Status write(const std::filesystem::path& file) const {
    std::ofstream out(file);
    out.precision(17);
    for (const auto& p : vertices) out << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
    for (const auto& [name, triangles] : objects) {
      out << "o " << name << '\n';
      for (const auto& t : triangles) out << "f " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    }
    out.close();
    if (!out) return make_error(ErrorCode::io_error, "cannot write " + file.string());
    return {};
  }
};

}  // namespace

Status write_open_roof_room(const std::filesystem::path& file) {
  ObjWriter obj;
  obj.quad("floor", {-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0});
  obj.quad("roof", {-5, -5, 3}, {5, -5, 3}, {5, 5, 3}, {-5, 5, 3});
  obj.quad("wall_south", {-5, -5, 0}, {5, -5, 0}, {5, -5, 3}, {-5, -5, 3});
  obj.quad("wall_east", {5, -5, 0}, {5, 5, 0}, {5, 5, 3}, {5, -5, 3});
  obj.quad("wall_north", {5, 5, 0}, {-5, 5, 0}, {-5, 5, 3}, {5, 5, 3});
  obj.quad("wall_west", {-5, 5, 0}, {-5, -5, 0}, {-5, -5, 3}, {-5, 5, 3});
  return obj.write(file);
}

SyntheticBounds thin_wall_bounds() { return {{-20, -20, 0}, {20, 20, 4}}; }

Status write_thin_wall(const std::filesystem::path& file, double thickness) {
  ObjWriter obj;
  obj.quad("floor", {-20, -20, 0}, {20, -20, 0}, {20, 20, 0}, {-20, 20, 0});
  obj.box("wall", {-thickness / 2, -5, 0}, {thickness / 2, 5, 4});
  return obj.write(file);
}

Status write_surfaces_scene(const std::filesystem::path& file, const std::string& which) {
  ObjWriter obj;
  obj.quad("floor", {-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0});
  // An open box: four walls and a top, facing out, no bottom.
  auto shell = [&](const std::string& name, double h, double top) {
    obj.quad(name + "_top", {-h, -h, top}, {h, -h, top}, {h, h, top}, {-h, h, top});
    obj.quad(name + "_south", {-h, -h, 0}, {h, -h, 0}, {h, -h, top}, {-h, -h, top});
    obj.quad(name + "_east", {h, -h, 0}, {h, h, 0}, {h, h, top}, {h, -h, top});
    obj.quad(name + "_north", {h, h, 0}, {-h, h, 0}, {-h, h, top}, {h, h, top});
    obj.quad(name + "_west", {-h, h, 0}, {-h, -h, 0}, {-h, -h, top}, {-h, h, top});
  };
  if (which == "roof_inner_wall") {
    obj.quad("roof", {-5, -5, 3}, {5, -5, 3}, {5, 5, 3}, {-5, 5, 3});
    obj.quad("inner_wall", {-4, 0.3, 0}, {4, 0.3, 0}, {4, 0.3, 2.9}, {-4, 0.3, 2.9});
  } else if (which == "leaf") {
    obj.quad("leaf", {-2, -1, 2}, {2, -1, 2.5}, {2, 1, 2.5}, {-2, 1, 2});
  } else if (which == "stacked_shells") {
    shell("outer", 4, 4);
    shell("inner", 2, 2);
  } else if (which == "open_wall") {
    obj.quad("wall", {0, -5, 0}, {0, 5, 0}, {0, 5, 4}, {0, -5, 4});
  } else {
    return make_error(ErrorCode::invalid_input, "no surfaces scene named " + which);
  }
  return obj.write(file);
}

Status write_single_triangle(const std::filesystem::path& file, double size) {
  ObjWriter obj;
  int a = obj.vertex(0, 0, 0), b = obj.vertex(size, 0, 0), c = obj.vertex(0, size, 0);
  obj.objects.push_back({"triangle", {{a, b, c}}});
  return obj.write(file);
}

}  // namespace shadowtiles::bench
