// `shadowtiles verify STORE --scene SCENE [--method M]`: recompute the dual depth and check every
// texel of every stored method (exit 0 only when all are inside their intervals, 3 otherwise).
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "builder/scene_loader.hpp"
#include "builder/store_verifier.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {
namespace {

struct VerifyFlags {
  std::string store, scene, methods;
  unsigned threads = 2;
  bool json = false;
};

int run(const VerifyFlags& flags) {
  auto map = ShadowMap::open(flags.store);
  if (!map) { spdlog::error("cannot open store: {}", map.error().message); return exit_code_for(map.error()); }
  std::vector<store::Method> methods = (*map)->meta().methods;
  if (!flags.methods.empty()) {
    auto parsed = store::parse_method_list(flags.methods);
    if (!parsed) { spdlog::error("--method: {}", parsed.error().message); return kInvalidInput; }
    methods = *parsed;
  }
  LoadOptions load;
  load.heightfield_meshes = (*map)->meta().heightfield_meshes;
  auto scene = load_scene(flags.scene.empty() ? (*map)->meta().scene_path : flags.scene, load);
  if (!scene) { spdlog::error("{}", scene.error().message); return exit_code_for(scene.error()); }
  if (scene->triangle_count() != (*map)->meta().scene_triangles)
    spdlog::warn("the scene has {} triangles, the store was built from {}", scene->triangle_count(),
                 (*map)->meta().scene_triangles);
  auto report = verify_store(**map, *scene, methods, flags.threads);
  if (!report) { spdlog::error("verify failed: {}", report.error().message); return exit_code_for(report.error()); }
  nlohmann::json out = nlohmann::json::object();
  out["receivers"] = receiver_contract_name(report->receivers);
  out["exit_caps"] = report->exit_caps;
  out["entry_slack"] = report->entry_slack;
  if (!flags.json)
    std::printf("receivers %s, exit caps %s, entry slack %g (brute-force reference over %llu texels)\n",
                receiver_contract_name(report->receivers), report->exit_caps ? "on" : "off", report->entry_slack,
                (unsigned long long)report->reference_cap_texels);
  for (const auto& [method, v] : report->methods) {
    out[store::method_name(method)] = {{"tiles", v.tiles}, {"texels", v.texels}, {"outside", v.outside},
                                       {"wrong_answers", v.wrong_answers}};
    if (!flags.json)
      std::printf("%-6s tiles %llu  texels %llu  outside interval %llu  wrong answers %llu  %s\n",
                  store::method_name(method), (unsigned long long)v.tiles, (unsigned long long)v.texels,
                  (unsigned long long)v.outside, (unsigned long long)v.wrong_answers,
                  v.outside || v.wrong_answers ? ("FAIL: " + v.first_violation).c_str() : "ok");
  }
  if (flags.json) std::cout << out.dump(2) << "\n";
  return report->ok() ? kOk : kCheckFailed;
}

}  // namespace

void add_verify_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<VerifyFlags>();
  CLI::App* cmd = app.add_subcommand("verify", "Check every texel of every stored method against recomputed intervals");
  cmd->add_option("store", flags->store, "Store directory")->required();
  cmd->add_option("--scene", flags->scene, "Scene file (default: the path recorded at build time)");
  cmd->add_option("--method,-m", flags->methods, "Methods to check (default: all stored)");
  cmd->add_option("--threads,-j", flags->threads, "Worker threads")->capture_default_str();
  cmd->add_flag("--json", flags->json, "Print JSON");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
