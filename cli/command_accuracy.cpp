// `shadowtiles accuracy STORE SCENE [--receivers N] [--seed S] [--json]`: every stored method's
// lit/shadowed answers on N receivers sampled uniformly on the scene's surfaces, against an Embree
// occlusion ray toward the sun (builder/accuracy.hpp, the bench's own evaluator: same receivers,
// same truth, same default bias). Raw, when stored, answers first and the others are compared with
// it. Queries go through ShadowMap tile by tile, so no whole map is decoded (it works on 65536^2
// stores). The scene is loaded with the up axis and heightfield meshes the store records. Receivers
// inside closed meshes and under heightfields are left out and counted (builder/solid_interior.hpp);
// nearly closed meshes are not loaded as solids here, so a receiver their patches would wrongly enclose
// still shows as a leak.
// Used by bench/build_sizes.py --accuracy for the two-contract size and leak table.
// --list-worse names every receiver counted as worse than raw (lit where raw and the truth shadow it,
// a leak; or shadowed where both light it): position, mesh, light-space texel and depth, raw's and the
// method's values as their queries used them, and the nearly closed meshes the build accepted as
// solids that enclose it (winding number of mesh + patches >= 1/2: inside a solid by the contract, no
// receiver place), so a leak found on a 65536^2 run can be traced without rebuilding it.
// Exit codes: 0, 1 (failure), 2 (bad arguments), 4 (store or scene unreadable).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "builder/accuracy.hpp"
#include "builder/embree_device.hpp"
#include "builder/nearly_closed_meshes.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "builder/solid_interior.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "client/shadow_map.hpp"
#include "codec/receiver_contract.hpp"

namespace shadowtiles::cli {
namespace {

struct AccuracyFlags {
  std::string store, scene;
  size_t receivers = 20000;
  uint64_t seed = 1;
  size_t cache_mib = 4096;
  bool json = false;
  bool list_worse = false;
};

// Names of the nearly closed meshes of `closed` (the scene closed as the build closed it) whose
// solid contains `p`.
nlohmann::json enclosing_nearly_closed(const Scene& closed, const Vec3& p) {
  nlohmann::json names = nlohmann::json::array();
  for (uint32_t m = 0; m < closed.meshes.size(); ++m) {
    const MeshInfo& mesh = closed.meshes[m];
    if (!mesh.nearly_closed) continue;
    std::vector<std::array<uint32_t, 3>> cycle(closed.triangles.begin() + mesh.first_triangle,
                                               closed.triangles.begin() + mesh.first_triangle + mesh.triangle_count);
    for (size_t t = 0; t < closed.patch_triangles.size(); ++t)
      if (closed.patch_mesh[t] == m) cycle.push_back(closed.patch_triangles[t]);
    if (winding_number(closed.vertices, cycle, p) >= 0.5) names.push_back(mesh.name);
  }
  return names;
}

// The receivers `worse` (indices from point_accuracy), each queried again for the method and raw.
Result<nlohmann::json> worse_receivers(const ShadowMap& map, const Scene& scene, const Scene* closed,
                                       store::Method method, std::span<const Receiver> receivers,
                                       std::span<const size_t> worse) {
  nlohmann::json list = nlohmann::json::array();
  for (const size_t i : worse) {
    const Receiver& r = receivers[i];
    auto answer = map.query(r.position, method);
    if (!answer) return answer.error();
    auto raw = map.query(r.position, store::Method::raw);
    if (!raw) return raw.error();
    const LightSpacePoint& p = answer->light;
    const uint32_t mesh = r.triangle < scene.triangle_mesh.size() ? scene.triangle_mesh[r.triangle] : 0;
    list.push_back({{"position", {r.position[0], r.position[1], r.position[2]}},
                    {"normal", {r.normal[0], r.normal[1], r.normal[2]}},
                    {"triangle", r.triangle},
                    {"mesh", mesh < scene.meshes.size() ? scene.meshes[mesh].name : std::string()},
                    {"mesh_kind", mesh < scene.meshes.size() ? mesh_kind_name(scene.meshes[mesh].kind) : ""},
                    {"lit", answer->lit},
                    {"texel", {uint32_t(p.u), uint32_t(p.v)}},
                    {"light_uv", {p.u, p.v}},
                    {"depth", p.depth},
                    {"raw_value", raw->value},
                    {"value", answer->value},
                    {"inside_nearly_closed",
                     closed ? enclosing_nearly_closed(*closed, r.position) : nlohmann::json::array()}});
  }
  return list;
}

int run(const AccuracyFlags& flags) {
  ShadowMap::Options options;
  options.cache_bytes = size_t(flags.cache_mib) << 20;
  auto map = ShadowMap::open(flags.store, options);
  if (!map) {
    spdlog::error("cannot open store: {}", map.error().message);
    return exit_code_for(map.error());
  }
  const StoreMeta& meta = (*map)->meta();
  LoadOptions load;
  load.up = meta.up_axis == "y" ? UpAxis::y : UpAxis::z;
  load.heightfield_meshes = meta.heightfield_meshes;
  auto scene = load_scene(flags.scene, load);
  if (!scene) {
    spdlog::error("{}", scene.error().message);
    return exit_code_for(scene.error());
  }
  if (scene->triangle_count() != meta.scene_triangles) {
    spdlog::error("{} has {} triangles, the store was built from {}: not the store's scene", flags.scene,
                  scene->triangle_count(), meta.scene_triangles);
    return kInvalidInput;
  }
  auto device = EmbreeDevice::create();
  if (!device) {
    spdlog::error("{}", device.error().message);
    return kFailure;
  }
  std::vector<Receiver> receivers = sample_receivers(*scene, flags.receivers, flags.seed);
  // Receivers inside solids are no receivers under either contract: left out for every method.
  const size_t inside_solids = drop_receivers_inside_solids(*device, *scene, (*map)->frame().direction(), receivers);
  // Counts do not depend on the order: receivers sorted by tile decode each tile once per method,
  // where the sampling order would decode one per receiver once the tiles outgrow the cache.
  const LightFrame& frame = (*map)->frame();
  const double tile_side = double(meta.tile_size);  // u, v are in texels
  auto tile_of = [&](const Receiver& r) {
    const LightSpacePoint p = frame.to_light(r.position);
    return std::pair{std::floor(p.v / tile_side), std::floor(p.u / tile_side)};
  };
  std::stable_sort(receivers.begin(), receivers.end(),
                   [&](const Receiver& a, const Receiver& b) { return tile_of(a) < tile_of(b); });
  GroundTruth truth(*device, *scene, (*map)->frame().direction());
  const std::vector<uint8_t> truths = point_truth(truth, receivers);

  // Raw first: the reference the others are compared with.
  std::vector<store::Method> methods = meta.methods;
  std::stable_partition(methods.begin(), methods.end(),
                        [](store::Method m) { return store::method_properties(m).reference; });
  std::vector<uint8_t> raw_answers;
  std::unique_ptr<Scene> closed_scene;  // for --list-worse: the scene closed as the build closed it
  if (!flags.json && inside_solids)
    std::printf("%zu of %zu receivers lie inside solids (no receiver place under either contract): left out\n",
                inside_solids, flags.receivers);
  nlohmann::json out = {{"receivers", receivers.size()}, {"inside_solids", inside_solids}, {"seed", flags.seed},
                        {"contract", receiver_contract_name(meta.receivers)}, {"methods", nlohmann::json::object()}};
  for (store::Method method : methods) {
    const bool is_raw = store::method_properties(method).reference;
    std::vector<size_t> worse;
    auto acc = point_accuracy(**map, method, receivers, truths, is_raw ? std::span<const uint8_t>{} : raw_answers,
                              is_raw ? &raw_answers : nullptr, &worse);
    if (!acc) {
      spdlog::error("{}: {}", store::method_name(method), acc.error().message);
      return exit_code_for(acc.error());
    }
    out["methods"][store::method_name(method)] = {
        {"false_lit", acc->false_lit},           {"false_shadowed", acc->false_shadowed},
        {"truth_lit", acc->truth_lit},           {"differs_from_raw", acc->differs_from_raw},
        {"worse_than_raw", acc->worse_than_raw}, {"outside_map", acc->outside_map}};
    if (flags.list_worse && !is_raw && !raw_answers.empty()) {
      if (meta.nearly_closed && !closed_scene) {
        closed_scene = std::make_unique<Scene>(*scene);
        close_nearly_closed_meshes(*closed_scene, nearly_closed_options(meta));
      }
      auto listed = worse_receivers(**map, *scene, closed_scene.get(), method, receivers, worse);
      if (!listed) {
        spdlog::error("{}: {}", store::method_name(method), listed.error().message);
        return exit_code_for(listed.error());
      }
      if (!flags.json)
        for (const nlohmann::json& w : *listed)
          std::printf("%s worse than raw: %s\n", store::method_name(method), w.dump().c_str());
      out["methods"][store::method_name(method)]["worse"] = std::move(*listed);
    }
    if (!flags.json)
      std::printf("%-6s false lit %6llu  false shadowed %6llu  (of %zu receivers; differs from raw %llu)\n",
                  store::method_name(method), static_cast<unsigned long long>(acc->false_lit),
                  static_cast<unsigned long long>(acc->false_shadowed), receivers.size(),
                  static_cast<unsigned long long>(acc->differs_from_raw));
  }
  if (flags.json) std::cout << out.dump(1) << "\n";
  return kOk;
}

}  // namespace

void add_accuracy_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<AccuracyFlags>();
  CLI::App* cmd = app.add_subcommand(
      "accuracy", "False-lit / false-shadowed answers of every stored method against Embree ground truth");
  cmd->add_option("store", flags->store, "Store directory")->required();
  cmd->add_option("scene", flags->scene, "The scene file the store was built from")->required();
  cmd->add_option("--receivers,-n", flags->receivers, "Receivers sampled uniformly on the surfaces")
      ->capture_default_str();
  cmd->add_option("--seed", flags->seed, "Receiver sampling seed (the bench's default)")->capture_default_str();
  cmd->add_option("--cache-mib", flags->cache_mib, "Decoded tile cache")->capture_default_str();
  cmd->add_flag("--json", flags->json, "Print JSON");
  cmd->add_flag("--list-worse", flags->list_worse,
                "Name every receiver a method answers worse than raw (needs raw stored)");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
