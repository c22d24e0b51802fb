#include "bench/harness/bench_config.hpp"

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

namespace shadowtiles::bench {
namespace {

Error bad(const std::string& what) { return make_error(ErrorCode::invalid_input, "bench config: " + what); }

Status check_keys(const nlohmann::json& object, std::initializer_list<const char*> allowed, const std::string& where) {
  if (!object.is_object()) return bad(where + " must be an object");
  std::set<std::string> names(allowed.begin(), allowed.end());
  for (auto& [key, value] : object.items())
    if (!names.count(key)) return bad("unknown key '" + key + "' in " + where);
  return {};
}

// json.get<T>() throws on type mismatches; this turns that into an Error naming the key.
template <class T>
Status read(const nlohmann::json& object, const char* key, T& out) {
  if (!object.contains(key)) return {};
  try {
    out = object.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    return bad(std::string("'") + key + "' has the wrong type");
  }
  return {};
}

Status read_methods(const nlohmann::json& object, std::vector<store::Method>& out) {
  std::vector<std::string> names;
  if (Status s = read(object, "methods", names); !s) return s;
  if (!object.contains("methods")) return {};
  std::string joined;
  for (auto& n : names) joined += (joined.empty() ? "" : ",") + n;
  auto parsed = store::parse_method_list(joined);
  if (!parsed) return bad("methods: " + parsed.error().message);
  out = *parsed;
  return {};
}

Status check_resolutions(const std::vector<uint32_t>& resolutions, const std::string& where) {
  for (uint32_t r : resolutions)
    if (r == 0 || (r & (r - 1)) || r > (1u << 20)) return bad(where + ": resolution " + std::to_string(r) +
                                                              " is not a power of two in [1, 2^20]");
  return {};
}

Status read_camera(const nlohmann::json& object, CameraSpec& camera) {
  if (Status s = check_keys(object, {"width", "height", "azimuth", "elevation", "fov"}, "camera"); !s) return s;
  for (auto s : {read(object, "width", camera.width), read(object, "height", camera.height),
                 read(object, "azimuth", camera.azimuth), read(object, "elevation", camera.elevation),
                 read(object, "fov", camera.fov)})
    if (!s) return s;
  if (camera.width > 4096 || camera.height > 4096) return bad("camera is limited to 4096 x 4096");
  if (!(camera.fov > 1 && camera.fov < 170)) return bad("camera fov must be in (1, 170) degrees");
  return {};
}

}  // namespace

Result<BenchConfig> parse_bench_config(const nlohmann::json& json, const std::filesystem::path& base_dir) {
  BenchConfig config;
  config.source = json;
  if (Status s = check_keys(json, {"description", "scene_root", "methods", "resolutions", "tile_size", "build_threads",
                                   "receivers", "camera", "pcf_kernels", "pcf_supersample", "threads", "min_seconds",
                                   "cache_mib", "keep_stores", "seed", "batch_points", "contract", "scenes"},
                            "the config");
      !s)
    return s.error();
  std::string scene_root = ".";
  std::vector<uint32_t> resolutions{1024};
  size_t receivers = 2000;
  std::string contract_name = "anywhere";
  CameraSpec camera;
  for (auto s : {read(json, "scene_root", scene_root), read(json, "contract", contract_name), read(json, "resolutions", resolutions),
                 read(json, "tile_size", config.tile_size), read(json, "build_threads", config.build_threads),
                 read(json, "receivers", receivers), read(json, "pcf_kernels", config.pcf_kernels),
                 read(json, "pcf_supersample", config.pcf_supersample), read(json, "threads", config.threads),
                 read(json, "min_seconds", config.min_seconds), read(json, "cache_mib", config.cache_mib),
                 read(json, "keep_stores", config.keep_stores), read(json, "seed", config.seed),
                 read(json, "batch_points", config.batch_points),
                 read_methods(json, config.methods)})
    if (!s) return s.error();
  if (json.contains("camera"))
    if (Status s = read_camera(json["camera"], camera); !s) return s.error();
  auto contract = parse_receiver_contract(contract_name);
  if (!contract) return bad("contract must be \"anywhere\" or \"surfaces\"");
  if (Status s = check_resolutions(resolutions, "resolutions"); !s) return s.error();
  if (config.tile_size == 0 || (config.tile_size & (config.tile_size - 1))) return bad("tile_size must be a power of two");
  if (config.build_threads < 1 || config.build_threads > 256) return bad("build_threads must be in [1, 256]");
  for (unsigned k : config.pcf_kernels)
    if (k < 1 || k % 2 == 0 || k > 63) return bad("pcf_kernels must be odd and in [1, 63]");
  if (config.pcf_supersample < 1 || config.pcf_supersample > 8) return bad("pcf_supersample must be in [1, 8]");
  if (config.threads.empty()) return bad("threads must list at least one count");
  for (unsigned t : config.threads)
    if (t < 1 || t > 256) return bad("threads must be in [1, 256]");
  if (!(config.min_seconds >= 0 && config.min_seconds <= 60)) return bad("min_seconds must be in [0, 60]");
  if (config.cache_mib < 1) return bad("cache_mib must be >= 1");
  // raw is the reference: accuracy is compared with it and non-empty texels are counted on it.
  if (std::find(config.methods.begin(), config.methods.end(), store::Method::raw) == config.methods.end())
    config.methods.insert(config.methods.begin(), store::Method::raw);

  if (!json.contains("scenes") || !json["scenes"].is_array() || json["scenes"].empty())
    return bad("'scenes' must be a non-empty array");
  std::filesystem::path root = std::filesystem::path(scene_root).is_absolute() ? std::filesystem::path(scene_root)
                                                                               : base_dir / scene_root;
  std::set<std::string> names;
  for (const auto& item : json["scenes"]) {
    if (Status s = check_keys(item, {"name", "file", "up", "sun", "heightfield", "resolutions", "receivers", "contract", "camera"},
                              "a scene");
        !s)
      return s.error();
    SceneSpec scene;
    scene.resolutions = resolutions;
    scene.receivers = receivers;
    scene.camera = camera;
    std::string file, up = "z", scene_contract = receiver_contract_name(*contract);
    std::vector<double> sun{135, 45};
    for (auto s : {read(item, "name", scene.name), read(item, "file", file), read(item, "up", up),
                   read(item, "sun", sun), read(item, "heightfield", scene.heightfield),
                   read(item, "resolutions", scene.resolutions), read(item, "receivers", scene.receivers),
                   read(item, "contract", scene_contract)})
      if (!s) return s.error();
    if (auto c = parse_receiver_contract(scene_contract)) scene.contract = *c;
    else return bad("scene '" + scene.name + "': contract must be \"anywhere\" or \"surfaces\"");
    if (item.contains("camera"))
      if (Status s = read_camera(item["camera"], scene.camera); !s) return s.error();
    if (scene.name.empty() || file.empty()) return bad("every scene needs a 'name' and a 'file'");
    if (scene.name.find_first_of(",/ ") != std::string::npos) return bad("scene name '" + scene.name + "' has , / or space");
    if (!names.insert(scene.name).second) return bad("scene '" + scene.name + "' is listed twice");
    if (up == "z") scene.up = UpAxis::z;
    else if (up == "y") scene.up = UpAxis::y;
    else return bad("scene '" + scene.name + "': up must be \"y\" or \"z\"");
    if (sun.size() != 2) return bad("scene '" + scene.name + "': sun must be [azimuth, elevation]");
    scene.sun_azimuth = sun[0];
    scene.sun_elevation = sun[1];
    if (Status s = check_resolutions(scene.resolutions, "scene '" + scene.name + "'"); !s) return s.error();
    std::sort(scene.resolutions.begin(), scene.resolutions.end());  // small first: peak memory grows
    scene.file = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : root / file;
    config.scenes.push_back(std::move(scene));
  }
  return config;
}

Result<BenchConfig> load_bench_config(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return make_error(ErrorCode::not_found, "cannot read bench config " + file.string());
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json json = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false, /*comments=*/true);
  if (json.is_discarded()) return make_error(ErrorCode::invalid_input, file.string() + " is not valid JSON");
  return parse_bench_config(json, file.parent_path());
}

Status filter_bench_config(BenchConfig& config, const std::string& scenes, const std::string& methods) {
  if (!scenes.empty()) {
    std::vector<SceneSpec> kept;
    std::stringstream list(scenes);
    for (std::string name; std::getline(list, name, ',');) {
      auto it = std::find_if(config.scenes.begin(), config.scenes.end(), [&](auto& s) { return s.name == name; });
      if (it == config.scenes.end()) return bad("--scenes: no scene '" + name + "' in the config");
      kept.push_back(*it);
    }
    config.scenes = std::move(kept);
  }
  if (!methods.empty()) {
    auto parsed = store::parse_method_list(methods);
    if (!parsed) return bad("--methods: " + parsed.error().message);
    config.methods = *parsed;
    if (std::find(config.methods.begin(), config.methods.end(), store::Method::raw) == config.methods.end())
      config.methods.insert(config.methods.begin(), store::Method::raw);
  }
  return {};
}

}  // namespace shadowtiles::bench
