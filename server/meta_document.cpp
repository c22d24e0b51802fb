#include "server/meta_document.hpp"

#include <filesystem>

namespace shadowtiles::server {
namespace {
nlohmann::json vec(const Vec3& v) { return nlohmann::json::array({v[0], v[1], v[2]}); }
}  // namespace

std::string tiles_url_template(const std::string& build_id) {
  return "/v1/builds/" + build_id + "/tiles/{method}/{z}/{x}/{y}";
}

nlohmann::json meta_document(const ShadowMap& map) {
  const StoreMeta& meta = map.meta();
  const LightFrame& frame = map.frame();
  const TileLayout& layout = map.layout();
  nlohmann::json methods = nlohmann::json::array();
  nlohmann::json tiles_by_method = nlohmann::json::object();
  for (store::Method m : meta.methods) {
    methods.push_back(store::method_name(m));
    tiles_by_method[store::method_name(m)] =
        "/v1/builds/" + meta.config_hash + "/tiles/" + store::method_name(m) + "/{z}/{x}/{y}";
  }
  const double r = layout.resolution();
  std::string name = std::filesystem::path(meta.scene_path).filename().string();
  return {
      {"tilejson", "3.0.0"},
      {"name", name},
      {"version", "1.0.0"},
      {"scheme", "xyz"},
      {"tiles", nlohmann::json::array({tiles_url_template(meta.config_hash)})},
      {"minzoom", layout.tile_level()},
      {"maxzoom", layout.tile_level()},
      {"bounds", nlohmann::json::array({0.0, 0.0, r, r})},
      {"shadow",
       {{"format_version", meta.format_version},
        {"builder_version", meta.builder_version},
        {"build_id", meta.config_hash},
        {"build_record", "/v1/build"},
        {"skiplist", "/v1/builds/" + meta.config_hash + "/skiplist?method={method}"},
        {"scene", {{"name", name}, {"triangles", meta.scene_triangles}}},
        {"world_bounds", {{"min", vec(meta.scene_bounds.min)}, {"max", vec(meta.scene_bounds.max)}}},
        {"light_bounds", {{"u", {0.0, r}}, {"v", {0.0, r}}, {"depth", {0.0, 1.0}}}},
        {"light",
         {{"direction", vec(frame.direction())},
          {"axis_x", vec(frame.axis_x())},
          {"axis_y", vec(frame.axis_y())},
          {"origin", vec(frame.origin())},
          {"extent", frame.extent()},
          {"depth_range", frame.depth_range()},
          {"texel_size", frame.texel_size()}}},
        {"resolution", layout.resolution()},
        {"tile_size", layout.tile_size()},
        {"tile_level", layout.tile_level()},
        {"tiles_per_side", layout.tiles_per_side()},
        {"levels", map.level_count()},
        {"methods", methods},
        {"default_method", store::method_name(map.default_method())},
        {"tiles_by_method", tiles_by_method},
        {"default_bias", meta.default_bias},
        {"exit_margin", meta.exit_margin},
        // Which query points the answers are exact for (docs/receiver-contracts.md).
        {"receivers", receiver_contract_name(meta.receivers)},
        {"exit_caps", meta.exit_caps},
        // The least query bias the MH family and CPVS answer for (entry rule; 0: off).
        {"entry_slack", meta.entry_slack},
        {"build_stats", meta.build_stats}}},
  };
}

}  // namespace shadowtiles::server
