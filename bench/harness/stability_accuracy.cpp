// Scenarios 1, 2, 3, 6 and 9: accuracy against ground truth per method (rows), with checks that the
// lossless methods leak no light that raw (the interval's lower bound) does not.
#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/harness/stability_scenarios.hpp"
#include "bench/harness/stability_scenes.hpp"

namespace shadowtiles::bench {
namespace {

const StabilityRow* raw_row(const std::vector<StabilityRow>& rows, const std::string& subject, uint32_t resolution,
                            double elevation) {
  for (const StabilityRow& r : rows)
    if (r.subject == subject && r.method == "raw" && r.resolution == resolution &&
        (r.elevation == elevation || (std::isnan(r.elevation) && std::isnan(elevation))))
      return &r;
  return nullptr;
}

bool is_exact_name(const std::string& method) {
  auto parsed = store::parse_method(method);
  // Interval-exact methods store a value inside each texel's interval (store/method.hpp), so they
  // must never leak where raw (the interval's lower bound) does not.
  return parsed && store::method_properties(*parsed).interval_exact && !store::method_properties(*parsed).reference;
}

// Light a lossless method lets through where raw does not, on every row of the result: its false-lit
// receivers beyond raw's (a lossless method's lit set contains raw's, so the difference counts exactly
// those receivers). None is allowed.
void check_no_extra_leak(ScenarioResult& result) {
  for (const StabilityRow& r : result.rows) {
    if (!is_exact_name(r.method)) continue;
    const StabilityRow* raw = raw_row(result.rows, r.subject, r.resolution, r.elevation);
    if (!raw) continue;
    const int64_t extra = int64_t(r.false_lit) - int64_t(raw->false_lit);
    std::string where = fmt::format("{} {}^2{}", r.subject, r.resolution,
                                    std::isnan(r.elevation) ? "" : fmt::format(" el {:g}", r.elevation));
    result.check(fmt::format("{} {}: no light leak beyond raw's (tolerance 0)", where, r.method), extra <= 0,
                 fmt::format("false lit {} vs raw {} of {} receivers", r.false_lit, raw->false_lit, r.receivers));
  }
}

// The map side of the single-resolution scenarios (1, 2, 3, 9).
uint32_t accuracy_resolution(const StabilityContext& context) { return context.options().quick ? 512 : 2048; }

}  // namespace

Result<ScenarioResult> run_open_geometry(StabilityContext& context) {
  ScenarioResult result("open_geometry", "1. Open geometry");
  const uint32_t resolution = accuracy_resolution(context);
  const std::filesystem::path room = context.options().work_dir / "open_roof_room.obj";
  if (Status s = write_open_roof_room(room); !s) return s.error();
  struct Subject {
    std::string name;
    std::filesystem::path file;
    UpAxis up;
    double azimuth, elevation;
  };
  std::vector<Subject> subjects{{"room (one-sided roof)", room, UpAxis::z, 135, 60},
                                {"bunny", context.scene_file("bunny/stanford-bunny.obj"), UpAxis::y, 135, 45},
                                {"fzk_haus", context.scene_file("fzk_haus/fzk_haus.obj"), UpAxis::y, 135, 45}};
  if (!context.options().quick)
    subjects.push_back({"dragon_res2", context.scene_file("dragon_res2/dragon_vrip_res2.ply"), UpAxis::y, 135, 45});
  result.setup = fmt::format("{}^2, tiles 1024^2 (whole map when smaller), {} uniform receivers per scene; "
                             "each scene built three times: our rule (open mesh: exit = entry), as a comparison "
                             "the far-plane exit rule of the MMH authors' code, and (scans) with nearly closed "
                             "meshes accepted as solids (the default build), each row's note giving its exit texels",
                             resolution, context.options().receivers);
  for (const Subject& subject : subjects) {
    LoadOptions load;
    load.up = subject.up;
    auto scene = context.scene(subject.file, load);
    if (!scene) return scene.error();
    MeasureSpec spec = sun_spec(subject.name, resolution, subject.azimuth, subject.elevation, subject.up);
    const size_t raw_row = result.rows.size();  // measure's rows start with raw's
    if (Status s = context.measure_into(**scene, spec, result); !s) return s.error();
    const uint64_t raw_false_lit = result.rows[raw_row].false_lit;
    spec.open_exit_at_far_plane = true;
    std::vector<store::Method> compared;
    for (store::Method m : supported_methods())
      if (store::method_properties(m).interval_exact) compared.push_back(m);
    spec.methods = compared;
    auto far = context.measure(**scene, spec);
    if (!far) return far.error();
    for (const StabilityRow& r : *far)
      if (r.method != "raw [far-plane exit]") {
        result.notes.push_back(fmt::format("{}: {} leaks {} receivers more than our rule ({} false lit vs {})",
                                           subject.name, r.method, int64_t(r.false_lit) - int64_t(raw_false_lit),
                                           r.false_lit, raw_false_lit));
        if (subject.name.rfind("room", 0) == 0)
          result.check(fmt::format("room: the far-plane rule leaks under the one-sided roof ({})", r.method),
                       r.false_lit > raw_false_lit,
                       fmt::format("{} false lit vs {} with exit = entry", r.false_lit, raw_false_lit));
      }
    for (StabilityRow& r : *far)
      if (r.method != "raw [far-plane exit]") result.rows.push_back(r);  // raw is unchanged by the rule
    // The scans again with nearly closed meshes accepted as solids (the build's default under
    // `anywhere`, docs/receiver-contracts.md): exits appear, and no lossless method may leak beyond raw.
    if (subject.name.rfind("room", 0) == 0) continue;
    spec.open_exit_at_far_plane = false;
    spec.close_nearly_closed = true;
    auto solid = context.measure(**scene, spec);
    if (!solid) return solid.error();
    for (const StabilityRow& r : *solid) {
      if (r.method == "raw [nearly closed]") continue;  // raw is the first hit: unchanged by the rule
      result.check(fmt::format("{}: {} no light leak beyond raw's", subject.name, r.method),
                   r.false_lit <= raw_false_lit,
                   fmt::format("false lit {} vs raw {} of {} receivers", r.false_lit, raw_false_lit, r.receivers));
      result.rows.push_back(r);
    }
  }
  // Open meshes give zero-width intervals: every lossless answer must be raw's.
  for (const StabilityRow& r : result.rows)
    if (is_exact_name(r.method) && (r.subject == "bunny" || r.subject.rfind("room", 0) == 0))
      result.check(fmt::format("{} {}: answers identical to raw's (all meshes open)", r.subject, r.method),
                   r.differs_from_raw == 0, fmt::format("{} answers differ", r.differs_from_raw));
  check_no_extra_leak(result);
  return result;
}

Result<ScenarioResult> run_thin_walls(StabilityContext& context) {
  ScenarioResult result("thin_walls", "2. Thin walls and closed objects");
  const uint32_t resolution = accuracy_resolution(context);
  const double azimuth = 90, elevation = 30;  // sun in the east: the wall's shadow falls west
  const Vec3 light = *light_direction_from_sun(azimuth, elevation, UpAxis::z);
  SyntheticBounds b = thin_wall_bounds();
  auto frame = LightFrame::fit(light, {{b.min[0], b.min[1], b.min[2]}, {b.max[0], b.max[1], b.max[2]}}, resolution);
  if (!frame) return frame.error();
  const double texel = frame->texel_size();
  result.setup = fmt::format("{}^2; walls: closed boxes 10 x 4 on a 40 x 40 floor, sun azimuth {:g} elevation {:g} "
                             "(texel {:.4g} m, exit margin 4 texels); nefertiti (watertight) sun 135, 45",
                             resolution, azimuth, elevation, texel);
  for (double texels : {4.0, 1.0, 0.5, 0.1}) {
    const std::string name = fmt::format("wall {:g} texel{}", texels, texels == 1 ? "" : "s");
    const std::filesystem::path file = context.options().work_dir / fmt::format("thin_wall_{:g}.obj", texels);
    if (Status s = write_thin_wall(file, texels * texel); !s) return s.error();
    auto scene = context.scene(file, LoadOptions{});
    if (!scene) return scene.error();
    MeasureSpec spec;
    spec.subject = name;
    spec.light = light;
    spec.resolution = resolution;
    if (Status s = context.measure_into(**scene, spec, result); !s) return s.error();
  }
  auto nefertiti = context.shared_scene("nefertiti/nefertiti.obj", UpAxis::z);
  if (!nefertiti) return nefertiti.error();
  if (Status s = context.measure_into(**nefertiti, sun_spec("nefertiti", resolution, 135, 45, UpAxis::z), result); !s)
    return s.error();
  check_no_extra_leak(result);
  return result;
}

Result<ScenarioResult> run_grazing_sun(StabilityContext& context) {
  ScenarioResult result("grazing_sun", "3. Grazing sun");
  const uint32_t resolution = accuracy_resolution(context);
  const std::vector<double> elevations =
      context.options().quick ? std::vector<double>{2, 10, 60} : std::vector<double>{2, 5, 10, 30, 60, 90};
  result.setup = fmt::format("{}^2, tiles 1024^2, sun azimuth 135, terrain declared a heightfield, {} uniform "
                             "receivers per scene",
                             resolution, context.options().receivers);
  struct Subject {
    std::string name, file;
  };
  for (const Subject& subject : {Subject{"terragen", "terragen/RealisticTerrain.ter"},
                                 Subject{"oahu", "oahu/oahu_w158n21.ply"}}) {
    auto scene = context.shared_scene(subject.file, UpAxis::z, true);
    if (!scene) return scene.error();
    for (double elevation : elevations) {
      MeasureSpec spec = sun_spec(subject.name, resolution, 135, elevation, UpAxis::z);
      spec.elevation = elevation;
      if (Status s = context.measure_into(**scene, spec, result); !s) return s.error();
    }
  }
  check_no_extra_leak(result);
  return result;
}

Result<ScenarioResult> run_resolution_sweep(StabilityContext& context) {
  ScenarioResult result("resolution_sweep", "6. Resolution sweep");
  const bool quick = context.options().quick;
  const std::vector<uint32_t> resolutions =
      quick ? std::vector<uint32_t>{256, 512, 1024} : std::vector<uint32_t>{256, 512, 1024, 2048, 4096};
  result.setup = fmt::format("resolutions {}..{}, tiles 1024^2, {} uniform receivers per scene",
                             resolutions.front(), resolutions.back(), context.options().receivers);
  struct Subject {
    std::string name, file;
    UpAxis up;
    bool heightfield;
  };
  std::vector<Subject> subjects{{"bunny", "bunny/stanford-bunny.obj", UpAxis::y, false},
                                {"nefertiti", "nefertiti/nefertiti.obj", UpAxis::z, false},
                                {"terragen", "terragen/RealisticTerrain.ter", UpAxis::z, true}};
  for (const Subject& subject : subjects) {
    auto scene = context.shared_scene(subject.file, subject.up, subject.heightfield);
    if (!scene) return scene.error();
    for (uint32_t resolution : resolutions) {
      const MeasureSpec spec = sun_spec(subject.name, resolution, 135, subject.heightfield ? 30 : 45, subject.up);
      if (Status s = context.measure_into(**scene, spec, result); !s) return s.error();
    }
  }
  // Tolerance: the error is a count of receivers out of a sample; two resolutions misclassify
  // different receivers, so its change has a binomial spread of about sqrt(errors). We allow
  // 2 sqrt(e) + 3 above the coarser resolution's count e.
  for (const StabilityRow& fine : result.rows) {
    auto method = store::parse_method(fine.method);
    if (!method || !store::method_properties(*method).interval_exact) continue;
    for (const StabilityRow& coarse : result.rows)
      if (coarse.subject == fine.subject && coarse.method == fine.method && coarse.resolution * 2 == fine.resolution) {
        const uint64_t e0 = coarse.false_lit + coarse.false_shadowed, e1 = fine.false_lit + fine.false_shadowed;
        const double tolerance = 2 * std::sqrt(double(e0)) + 3;
        result.check(fmt::format("{} {}: error at {}^2 not above {}^2's (+{:.0f})", fine.subject, fine.method,
                                 fine.resolution, coarse.resolution, tolerance),
                     double(e1) <= double(e0) + tolerance, fmt::format("{} -> {} wrong answers", e0, e1));
      }
  }
  return result;
}

// Scenario 9: the `surfaces` receiver contract (docs/receiver-contracts.md). Its intervals reach the
// second surface, so open meshes get width; the receivers here lie on the surfaces, as the contract
// says, and a lossless method must still leak nothing raw does not, off the texel centre included.
Result<ScenarioResult> run_surfaces_contract(StabilityContext& context) {
  ScenarioResult result("surfaces_contract", "9. Surfaces receiver contract");
  const uint32_t resolution = accuracy_resolution(context);
  struct Subject {
    std::string name, scene;  // scene: a write_surfaces_scene name, or a shared scene file
    UpAxis up;
    double azimuth, elevation;
  };
  const std::vector<Subject> subjects{{"open roof over a floor, inner wall under it", "roof_inner_wall", UpAxis::z, 135, 60},
                                      {"single-sided leaf over ground", "leaf", UpAxis::z, 135, 50},
                                      {"two stacked open shells", "stacked_shells", UpAxis::z, 135, 45},
                                      {"thin open wall, receivers on both sides", "open_wall", UpAxis::z, 90, 30},
                                      {"mesh with holes (bunny)", "bunny/stanford-bunny.obj", UpAxis::y, 135, 45}};
  result.setup = fmt::format("{}^2, tiles 1024^2 (whole map when smaller), {} uniform receivers per scene (on the "
                             "surfaces, as the contract says), `--receivers surfaces`, exit caps on; synthetic "
                             "scenes over a one-sided 20 x 20 floor (bench/harness/stability_scenes.hpp)",
                             resolution, context.options().receivers);
  for (const Subject& subject : subjects) {
    std::filesystem::path file;
    if (subject.scene.find('/') == std::string::npos) {
      file = context.options().work_dir / (subject.scene + ".obj");
      if (Status s = write_surfaces_scene(file, subject.scene); !s) return s.error();
    } else {
      file = context.scene_file(subject.scene);
    }
    LoadOptions load;
    load.up = subject.up;
    auto scene = context.scene(file, load);
    if (!scene) return scene.error();
    MeasureSpec spec = sun_spec(subject.name, resolution, subject.azimuth, subject.elevation, subject.up);
    spec.receivers = ReceiverContract::surfaces;
    auto rows = context.measure(**scene, spec);
    if (!rows) return rows.error();
    const StabilityRow* raw = raw_row(*rows, subject.name, resolution, spec.elevation);
    for (const StabilityRow& r : *rows)
      if (raw && r.method == "dagmh")
        result.notes.push_back(fmt::format("{}: DAG-MH {} bytes vs raw {} (x{:.3f}), false lit {} vs raw {}", subject.name,
                                           r.bytes, raw->bytes, raw->bytes ? double(r.bytes) / double(raw->bytes) : 0.0,
                                           r.false_lit, raw->false_lit));
    result.rows.insert(result.rows.end(), rows->begin(), rows->end());
  }
  check_no_extra_leak(result);
  return result;
}

}  // namespace shadowtiles::bench
