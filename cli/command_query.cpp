// `shadowtiles query (STORE | --server URL) --point X,Y,Z ...`: is a world point lit? From a local
// store, or streamed from a server by the client (client/streaming_client.hpp), optionally beside
// the Embree ground truth of the scene.
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "builder/ground_truth.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "cli/cli_parsing.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "client/shadow_map.hpp"
#include "client/streaming_client.hpp"

namespace shadowtiles::cli {
namespace {

struct QueryFlags {
  std::string store, server, method, ground_truth;
  std::vector<std::string> points;
  double bias = -1;
  size_t sample = 0;
  bool json = false;
};

int run(const QueryFlags& flags) {
  if (flags.store.empty() == flags.server.empty()) {
    spdlog::error("give a STORE directory or --server URL (one of them)");
    return kInvalidInput;
  }
  auto map = open_shadow_map(flags.server.empty() ? flags.store : flags.server, StreamingOptions{});
  if (!map) {
    spdlog::error("cannot open {}: {}", flags.server.empty() ? "store" : "server", map.error().message);
    return exit_code_for(map.error());
  }
  store::Method method = (*map)->default_method();
  if (!flags.method.empty()) {
    auto parsed = store::parse_method(flags.method);
    if (!parsed) { spdlog::error("--method: {}", parsed.error().message); return kInvalidInput; }
    method = *parsed;
  }
  std::optional<double> bias;
  if (flags.bias >= 0) bias = flags.bias;

  std::unique_ptr<EmbreeDevice> device;
  std::unique_ptr<Scene> scene;
  std::unique_ptr<GroundTruth> truth;
  if (!flags.ground_truth.empty()) {
    auto created = EmbreeDevice::create();
    if (!created) { spdlog::error("{}", created.error().message); return kFailure; }
    device = std::make_unique<EmbreeDevice>(std::move(*created));
    auto loaded = load_scene(flags.ground_truth, LoadOptions{});
    if (!loaded) { spdlog::error("{}", loaded.error().message); return exit_code_for(loaded.error()); }
    scene = std::make_unique<Scene>(std::move(*loaded));
    truth = std::make_unique<GroundTruth>(*device, *scene, (*map)->frame().direction());
  }

  // Points: the given ones, then receivers sampled on the scene's surfaces.
  std::vector<Vec3> points;
  for (const std::string& text : flags.points) {
    auto point = parse_vec3(text, "--point");
    if (!point) { spdlog::error("{}", point.error().message); return kInvalidInput; }
    points.push_back(*point);
  }
  if (flags.sample > 0) {
    if (!scene) { spdlog::error("--sample needs --ground-truth SCENE"); return kInvalidInput; }
    for (const Receiver& r : sample_receivers(*scene, flags.sample, 1)) points.push_back(r.position);
  }
  if (points.empty()) { spdlog::error("give --point X,Y,Z or --sample N"); return kInvalidInput; }

  nlohmann::json results = nlohmann::json::array();
  size_t agree = 0;
  for (const Vec3& p : points) {
    const Vec3* point = &p;
    auto answer = (*map)->query(*point, method, bias);
    if (!answer) {
      spdlog::error("query failed: {}", answer.error().message);
      return exit_code_for(answer.error());
    }
    nlohmann::json row = {{"point", {(*point)[0], (*point)[1], (*point)[2]}},
                          {"method", store::method_name(method)},
                          {"lit", answer->lit},
                          {"outside_map", answer->outside_map},
                          {"empty_tile", answer->empty_tile},
                          {"u", answer->light.u},
                          {"v", answer->light.v},
                          {"depth", answer->light.depth},
                          {"value", std::isfinite(answer->value) ? nlohmann::json(answer->value) : nlohmann::json("inf")}};
    if (truth) {
      row["ground_truth_lit"] = truth->lit(*point);
      agree += row["ground_truth_lit"].get<bool>() == answer->lit;
    }
    results.push_back(row);
    if (!flags.json) {
      std::printf("%s (%g, %g, %g): %s", store::method_name(method), (*point)[0], (*point)[1], (*point)[2],
                  answer->lit ? "lit" : "shadowed");
      if (answer->outside_map) std::printf(" (outside the map)");
      if (truth) std::printf("   ground truth: %s", row["ground_truth_lit"].get<bool>() ? "lit" : "shadowed");
      std::printf("\n");
    }
  }
  if (flags.json) std::cout << results.dump(2) << "\n";
  else if (truth)
    std::printf("agreement with ground truth: %zu of %zu points\n", agree, points.size());
  return kOk;
}

}  // namespace

void add_query_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<QueryFlags>();
  CLI::App* cmd = app.add_subcommand("query", "Is a world point lit? (from a local store or a server)");
  cmd->add_option("store", flags->store, "Store directory (or give --server)");
  cmd->add_option("--server", flags->server, "Stream the build from this server (http://host:port) instead");
  cmd->add_option("--point,-p", flags->points, "World point X,Y,Z (repeatable)")->take_all();
  cmd->add_option("--sample", flags->sample, "Also query N points sampled on the --ground-truth scene's surfaces");
  cmd->add_option("--bias", flags->bias, "Depth bias in world units (default: the build's)");
  cmd->add_option("--method,-m", flags->method, "Method to answer from (default: the first stored)");
  cmd->add_option("--ground-truth", flags->ground_truth, "Scene file: also cast an Embree ray toward the sun");
  cmd->add_flag("--json", flags->json, "Print JSON");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
