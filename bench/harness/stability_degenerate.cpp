// Scenario 7: degenerate input. Each case either builds and answers correctly or fails with a clear
// invalid_input error (the CLI's exit code 2); nothing may crash or hang.
#include <fstream>

#include <fmt/format.h>

#include "bench/harness/stability_scenarios.hpp"
#include "bench/harness/stability_scenes.hpp"

namespace shadowtiles::bench {
namespace {

Status write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
  out.close();
  if (!out) return make_error(ErrorCode::io_error, "cannot write " + file.string());
  return {};
}

// A probe after a successful build: the world point, and the answer it must get (nullopt: any).
struct Probe {
  Vec3 point;
  std::optional<bool> lit;
};

struct Case {
  std::string name;
  std::string obj;  // scene file text ("" = the single triangle writer)
  Vec3 light{0, 0, -1};
  uint32_t resolution = 64, tile = 64;
  bool expect_error = false;
  std::vector<Probe> probes;
};

}  // namespace

Result<ScenarioResult> run_degenerate_input(StabilityContext& context) {
  ScenarioResult result("degenerate_input", "7. Degenerate input");
  result.setup = "small OBJ scenes written by the suite, built with every supported method; "
                 "expected: a correct result (probed by point queries) or invalid_input (CLI exit code 2)";
  const std::string triangle = "v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n";
  const std::string plane = "v -500 -500 0\nv 500 -500 0\nv 500 500 0\nv -500 500 0\nf 1 2 3\nf 1 3 4\n";
  // Under the single triangle (sun overhead): shadowed; beside it: lit.
  const std::vector<Probe> triangle_probes{{{2, 2, -1}, false}, {{2, 2, 1}, true}, {{9, 9, 0.000001}, true}};
  std::vector<Case> cases{
      {"empty scene (vertices, no faces)", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", {0, 0, -1}, 64, 64, true, {}},
      {"single triangle", triangle, {0, 0, -1}, 64, 64, false, triangle_probes},
      {"NaN vertex in one of two triangles", triangle + "v nan 0 0\nf 1 2 4\n", {0, 0, -1}, 64, 64, false,
       triangle_probes},
      {"inf vertex in one of two triangles", triangle + "v inf 0 0\nf 1 2 4\n", {0, 0, -1}, 64, 64, false,
       triangle_probes},
      {"only NaN/inf vertices", "v nan 0 0\nv 0 inf 0\nv 0 0 -inf\nf 1 2 3\n", {0, 0, -1}, 64, 64, true, {}},
      {"zero-area triangles beside a good one", triangle + "v 5 5 5\nf 4 4 4\nf 1 2 1\nv 20 0 0\nf 1 2 5\n",
       {0, 0, -1}, 64, 64, false, triangle_probes},
      {"only zero-area triangles", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n", {0, 0, -1}, 64, 64, true, {}},
      {"light parallel to a large plane", plane, {1, 0, 0}, 64, 64, false, {{{0, 0, 0}, std::nullopt}, {{0, 0, 5}, true}}},
      {"zero light direction", triangle, {0, 0, 0}, 64, 64, true, {}},
      {"resolution 1", triangle, {0, 0, -1}, 1, 1, false, {{{2, 2, 1}, true}, {{2, 2, -1}, std::nullopt}}},
      {"tile larger than the map", triangle, {0, 0, -1}, 64, 4096, false, triangle_probes},
      // (9, 9, -1000) lies beyond the far plane at a miss texel (stored value 1): lit, because the
      // frame keeps a margin behind the deepest surface and queries clamp depths to the far plane;
      // under the triangle, as deep, shadowed. (9, 9, -1): within the margin.
      {"below a flat scene, outside its footprint (beyond the far plane)", triangle, {0, 0, -1}, 64, 64, false,
       {{{9, 9, -1}, true}, {{9, 9, -1000}, true}, {{2, 2, -1000}, false}}},
      {"resolution not a power of two", triangle, {0, 0, -1}, 1000, 1000, true, {}},
      {"resolution 2^21 (over the 2^20 limit)", triangle, {0, 0, -1}, 1u << 21, 1024, true, {}},
  };
  StabilityTable table{"Degenerate input: outcome per case", {"case", "expected", "outcome", "detail"}, {}};
  const std::filesystem::path dir = context.options().work_dir / "degenerate";
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const std::filesystem::path scene = dir / fmt::format("case{}.obj", i), store = dir / "store";
    if (Status s = write_text(scene, c.obj); !s) return s.error();
    std::filesystem::remove_all(store, ec);
    BuildConfig build;
    build.scene_path = scene;
    build.store_path = store;
    build.light_direction = c.light;
    build.resolution = c.resolution;
    build.tile_size = c.tile;
    build.methods = supported_methods();
    build.overwrite = true;
    auto summary = run_build(build);
    std::string outcome, detail;
    bool ok = false;
    if (!summary) {
      outcome = std::string("error ") + error_code_name(summary.error().code);
      detail = summary.error().message;
      ok = c.expect_error && summary.error().code == ErrorCode::invalid_input && !detail.empty();
    } else if (c.expect_error) {
      outcome = "built";
      detail = "expected an invalid_input error";
    } else {
      outcome = "built";
      detail = fmt::format("{} triangles dropped, {} tiles stored", summary->stats["scene"].value("dropped", 0),
                           summary->tiles_stored);
      ok = true;
      auto map = ShadowMap::open(store);
      if (!map) {
        ok = false;
        detail += "; open failed: " + map.error().message;
      } else {
        for (store::Method method : supported_methods())
          for (const Probe& probe : c.probes) {
            auto answer = (*map)->query(probe.point, method);
            if (!answer) {
              ok = false;
              detail += fmt::format("; {} query failed: {}", store::method_name(method), answer.error().message);
            } else if (probe.lit && answer->lit != *probe.lit) {
              ok = false;
              detail += fmt::format("; {} answers {} at ({:g}, {:g}, {:g})", store::method_name(method),
                                    answer->lit ? "lit" : "shadowed", probe.point[0], probe.point[1], probe.point[2]);
            }
          }
        if (ok && !c.probes.empty()) detail += fmt::format("; {} probes answered as expected", c.probes.size());
      }
    }
    table.rows.push_back({c.name, c.expect_error ? "invalid_input" : "a result", outcome, detail});
    result.check(c.name, ok, outcome + ": " + detail);
    std::filesystem::remove_all(store, ec);
  }
  result.tables.push_back(std::move(table));
  return result;
}

}  // namespace shadowtiles::bench
