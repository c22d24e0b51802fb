#include "codec/store_meta.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "codec/json_integer.hpp"

namespace shadowtiles {
namespace {

nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v[0], v[1], v[2]}); }

Result<Vec3> vec_from(const nlohmann::json& json, const char* name) {
  if (!json.contains(name) || !json[name].is_array() || json[name].size() != 3)
    return make_error(ErrorCode::corrupt_data, std::string("meta: '") + name + "' must be an array of 3 numbers");
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!json[name][i].is_number())
      return make_error(ErrorCode::corrupt_data, std::string("meta: '") + name + "' must hold numbers");
    v[i] = json[name][i].get<double>();
    if (!std::isfinite(v[i])) return make_error(ErrorCode::corrupt_data, std::string("meta: '") + name + "' not finite");
  }
  return v;
}

template <class T>
Result<T> field(const nlohmann::json& json, const char* name) {
  if (!json.contains(name)) return make_error(ErrorCode::corrupt_data, std::string("meta: missing '") + name + "'");
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    // A count is an integer that fits its type, or the meta is corrupt (codec/json_integer.hpp).
    const auto value =
        json_integer_in<T>(json.at(name), std::numeric_limits<T>::min(), std::numeric_limits<T>::max());
    if (!value)
      return make_error(ErrorCode::corrupt_data,
                        std::string("meta: bad '") + name + "': not an integer in [" +
                            std::to_string(std::numeric_limits<T>::min()) + ", " +
                            std::to_string(std::numeric_limits<T>::max()) + "]");
    return *value;
  }
  try {
    return json.at(name).get<T>();
  } catch (const nlohmann::json::exception& e) {
    return make_error(ErrorCode::corrupt_data, std::string("meta: bad '") + name + "': " + e.what());
  }
}

}  // namespace

Result<LightFrame> StoreMeta::light_frame() const {
  return LightFrame::from_parameters(light_direction, light_origin, light_extent, light_depth_range, resolution);
}

Result<TileLayout> StoreMeta::layout() const { return TileLayout::make(resolution, tile_size); }

double StoreMeta::min_query_bias(store::Method method) const {
  using store::Method;
  const bool from_entry_intervals =
      method == Method::mh || method == Method::mmh || method == Method::dagmh || method == Method::cpvs;
  return from_entry_intervals ? entry_slack : 0.0;
}

bool StoreMeta::has_method(store::Method method) const {
  return std::find(methods.begin(), methods.end(), method) != methods.end();
}

nlohmann::json StoreMeta::to_json() const {
  nlohmann::json methods_json = nlohmann::json::array();
  for (store::Method m : methods) methods_json.push_back(store::method_name(m));
  nlohmann::json json = {
      {"format_version", format_version},
      {"builder_version", builder_version},
      {"config_hash", config_hash},
      {"complete", complete},
      {"scene", {{"path", scene_path}, {"triangles", scene_triangles}, {"heightfield_meshes", heightfield_meshes},
                 {"bounds_min", vec_json(scene_bounds.min)}, {"bounds_max", vec_json(scene_bounds.max)}, {"up", up_axis}}},
      {"light", {{"direction", vec_json(light_direction)}, {"origin", vec_json(light_origin)},
                 {"extent", light_extent}, {"depth_range", light_depth_range}}},
      {"resolution", resolution},
      {"tile_size", tile_size},
      {"methods", methods_json},
      {"default_bias", default_bias},
      {"exit_margin", exit_margin},
      {"receivers", receiver_contract_name(receivers)},
      {"exit_caps", exit_caps},
      {"build_stats", build_stats},
  };
  if (entry_slack > 0) json["entry_slack"] = entry_slack;
  if (nearly_closed)
    json["nearly_closed"] = {{"tolerance", nearly_closed_tolerance},
                             {"max_ambiguous_area", nearly_closed_max_ambiguous_area},
                             {"max_samples", nearly_closed_max_samples},
                             {"max_patch_triangles", nearly_closed_max_patch_triangles},
                             {"min_full_samples", nearly_closed_min_full_samples},
                             {"full_budget", nearly_closed_full_budget},
                             {"max_misplaced_area", nearly_closed_max_misplaced_area}};
  if (shard)
    json["shard"] = {{"index", shard->index}, {"count", shard->count}, {"morton_begin", shard->morton_begin},
                     {"morton_end", shard->morton_end}, {"tiles", shard->tiles}, {"work", shard->work},
                     {"complete", shard->complete}, {"zstd_level", shard->zstd_level}};
  return json;
}

Result<StoreMeta> StoreMeta::from_json(const nlohmann::json& json) {
  if (!json.is_object()) return make_error(ErrorCode::corrupt_data, "meta: not a JSON object");
  StoreMeta meta;
  auto version = field<int>(json, "format_version");
  if (!version) return version.error();
  if (*version != kStoreFormatVersion)
    return make_error(ErrorCode::unsupported, "store format version " + std::to_string(*version) +
                                                  " is not supported (this build reads " +
                                                  std::to_string(kStoreFormatVersion) + ")");
  meta.format_version = *version;
  auto builder = field<std::string>(json, "builder_version");
  auto hash = field<std::string>(json, "config_hash");
  auto complete = field<bool>(json, "complete");
  auto resolution = field<uint32_t>(json, "resolution");
  auto tile_size = field<uint32_t>(json, "tile_size");
  auto bias = field<double>(json, "default_bias");
  auto margin = field<double>(json, "exit_margin");
  for (const Error* e : {builder.ok() ? nullptr : &builder.error(), hash.ok() ? nullptr : &hash.error(),
                         complete.ok() ? nullptr : &complete.error(), resolution.ok() ? nullptr : &resolution.error(),
                         tile_size.ok() ? nullptr : &tile_size.error(), bias.ok() ? nullptr : &bias.error(),
                         margin.ok() ? nullptr : &margin.error()})
    if (e) return *e;
  meta.builder_version = *builder;
  meta.config_hash = *hash;
  meta.complete = *complete;
  meta.resolution = *resolution;
  meta.tile_size = *tile_size;
  meta.default_bias = *bias;
  meta.exit_margin = *margin;
  if (!std::isfinite(meta.default_bias) || meta.default_bias < 0)
    return make_error(ErrorCode::corrupt_data, "meta: default_bias must be finite and >= 0");

  if (!json.contains("scene") || !json["scene"].is_object())
    return make_error(ErrorCode::corrupt_data, "meta: missing 'scene'");
  const auto& scene = json["scene"];
  auto path = field<std::string>(scene, "path");
  auto triangles = field<uint64_t>(scene, "triangles");
  auto bmin = vec_from(scene, "bounds_min");
  auto bmax = vec_from(scene, "bounds_max");
  if (!path) return path.error();
  if (!triangles) return triangles.error();
  if (!bmin) return bmin.error();
  if (!bmax) return bmax.error();
  meta.scene_path = *path;
  meta.scene_triangles = *triangles;
  meta.scene_bounds = {*bmin, *bmax};
  if (scene.contains("up")) {
    auto up = field<std::string>(scene, "up");
    if (!up) return up.error();
    if (!up->empty() && *up != "z" && *up != "y") return make_error(ErrorCode::corrupt_data, "meta: scene.up must be z or y");
    meta.up_axis = *up;
  }
  if (scene.contains("heightfield_meshes")) {
    auto names = field<std::vector<std::string>>(scene, "heightfield_meshes");
    if (!names) return names.error();
    meta.heightfield_meshes = *names;
  }

  if (!json.contains("light") || !json["light"].is_object())
    return make_error(ErrorCode::corrupt_data, "meta: missing 'light'");
  const auto& light = json["light"];
  auto direction = vec_from(light, "direction");
  auto origin = vec_from(light, "origin");
  auto extent = field<double>(light, "extent");
  auto depth_range = field<double>(light, "depth_range");
  if (!direction) return direction.error();
  if (!origin) return origin.error();
  if (!extent) return extent.error();
  if (!depth_range) return depth_range.error();
  meta.light_direction = *direction;
  meta.light_origin = *origin;
  meta.light_extent = *extent;
  meta.light_depth_range = *depth_range;

  if (!json.contains("methods") || !json["methods"].is_array())
    return make_error(ErrorCode::corrupt_data, "meta: 'methods' must be an array");
  for (const auto& name : json["methods"]) {
    if (!name.is_string()) return make_error(ErrorCode::corrupt_data, "meta: method names must be strings");
    auto method = store::parse_method(name.get<std::string>());
    if (!method) return make_error(ErrorCode::unsupported, "meta: " + method.error().message);
    meta.methods.push_back(*method);
  }
  if (json.contains("build_stats")) meta.build_stats = json["build_stats"];
  if (json.contains("shard")) {
    const auto& shard = json["shard"];
    if (!shard.is_object()) return make_error(ErrorCode::corrupt_data, "meta: 'shard' must be an object");
    auto index = field<uint32_t>(shard, "index");
    auto count = field<uint32_t>(shard, "count");
    auto begin = field<uint64_t>(shard, "morton_begin");
    auto end = field<uint64_t>(shard, "morton_end");
    auto tiles = field<uint64_t>(shard, "tiles");
    auto work = field<double>(shard, "work");
    auto done = field<bool>(shard, "complete");
    auto level = field<int>(shard, "zstd_level");
    for (const Error* e : {index.ok() ? nullptr : &index.error(), count.ok() ? nullptr : &count.error(),
                           begin.ok() ? nullptr : &begin.error(), end.ok() ? nullptr : &end.error(),
                           tiles.ok() ? nullptr : &tiles.error(), work.ok() ? nullptr : &work.error(),
                           done.ok() ? nullptr : &done.error(), level.ok() ? nullptr : &level.error()})
      if (e) return *e;
    if (*count < 1 || *index >= *count || *begin > *end)
      return make_error(ErrorCode::corrupt_data, "meta: shard index, count or range out of order");
    meta.shard = ShardInfo{*index, *count, *begin, *end, *tiles, *work, *done, *level};
  }
  if (json.contains("receivers")) {
    auto name = field<std::string>(json, "receivers");
    if (!name) return name.error();
    auto contract = parse_receiver_contract(*name);
    if (!contract)
      return make_error(ErrorCode::unsupported, "meta: receiver contract '" + *name + "' is not supported");
    meta.receivers = *contract;
  }
  if (json.contains("exit_caps")) {
    auto caps = field<bool>(json, "exit_caps");
    if (!caps) return caps.error();
    meta.exit_caps = *caps;
  }
  if (json.contains("entry_slack")) {
    auto slack = field<double>(json, "entry_slack");
    if (!slack) return slack.error();
    if (!std::isfinite(*slack) || *slack < 0 || meta.receivers != ReceiverContract::surfaces)
      return make_error(ErrorCode::corrupt_data, "meta: entry_slack must be finite, >= 0 and under surfaces");
    meta.entry_slack = *slack;
  }
  if (json.contains("nearly_closed")) {
    const nlohmann::json& closing = json["nearly_closed"];
    if (!closing.is_object()) return make_error(ErrorCode::corrupt_data, "meta: nearly_closed is not an object");
    auto tolerance = field<double>(closing, "tolerance");
    if (!tolerance) return tolerance.error();
    auto area = field<double>(closing, "max_ambiguous_area");
    if (!area) return area.error();
    auto samples = field<uint32_t>(closing, "max_samples");
    if (!samples) return samples.error();
    auto patch = field<uint32_t>(closing, "max_patch_triangles");
    if (!patch) return patch.error();
    auto full = field<uint32_t>(closing, "min_full_samples");
    if (!full) return full.error();
    auto budget = field<uint64_t>(closing, "full_budget");
    if (!budget) return budget.error();
    if (!(*tolerance >= 0 && *tolerance < 0.5 && *area >= 0 && *area <= 1 && *samples >= 1))
      return make_error(ErrorCode::corrupt_data, "meta: nearly_closed tolerance or area out of range");
    meta.nearly_closed = true;
    meta.nearly_closed_tolerance = *tolerance;
    meta.nearly_closed_max_ambiguous_area = *area;
    meta.nearly_closed_max_samples = *samples;
    meta.nearly_closed_max_patch_triangles = *patch;
    meta.nearly_closed_min_full_samples = *full;
    meta.nearly_closed_full_budget = *budget;
    if (closing.contains("max_misplaced_area")) {
      auto misplaced = field<double>(closing, "max_misplaced_area");
      if (!misplaced) return misplaced.error();
      if (!(*misplaced >= 0 && *misplaced <= 1))
        return make_error(ErrorCode::corrupt_data, "meta: nearly_closed max_misplaced_area out of range");
      meta.nearly_closed_max_misplaced_area = *misplaced;
    }
  }

  // The frame and layout must be constructible, or every lookup would fail later.
  if (auto frame = meta.light_frame(); !frame)
    return make_error(ErrorCode::corrupt_data, "meta: " + frame.error().message);
  if (auto layout = meta.layout(); !layout)
    return make_error(ErrorCode::corrupt_data, "meta: " + layout.error().message);
  return meta;
}

Result<StoreMeta> StoreMeta::parse(std::string_view text) {
  nlohmann::json json = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded()) return make_error(ErrorCode::corrupt_data, "meta: not valid JSON");
  return from_json(json);
}

}  // namespace shadowtiles
