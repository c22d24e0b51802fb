// `shadowtiles inspect STORE [--json]`: what a store holds: the build's meta and, per method, tiles
// and bytes (compressed at rest and decoded payload), and the payload split into the parts each
// method names (DecodedTile::size_breakdown), summed over every tile: a method shows up here by
// implementing that virtual.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <vector>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "cli/batch_allocator.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "codec/decoded_tile.hpp"
#include "codec/store_meta.hpp"
#include "store/blob.hpp"
#include "store/lmdb_store.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles::cli {
namespace {

struct InspectFlags {
  std::string store;
  bool json = false;
};

struct MethodTotals {
  uint64_t tiles = 0, blob_bytes = 0, payload_bytes = 0;
  // Payload parts and structure counts summed over tiles, in the order the decoder names them.
  std::vector<DecodedTile::SizePart> parts;
  std::vector<DecodedTile::StructureCount> counts;
  bool undecodable = false;  // no decoder in this build: no breakdown
};

void add_counts(std::vector<DecodedTile::StructureCount>& sum, const std::vector<DecodedTile::StructureCount>& counts) {
  for (const auto& c : counts) {
    auto it = std::find_if(sum.begin(), sum.end(), [&](const auto& s) { return s.group == c.group && s.name == c.name; });
    if (it == sum.end()) sum.push_back(c);
    else it->value = c.is_max ? std::max(it->value, c.value) : it->value + c.value;
  }
}

void add_parts(std::vector<DecodedTile::SizePart>& sum, const std::vector<DecodedTile::SizePart>& parts) {
  for (const auto& part : parts) {
    auto it = std::find_if(sum.begin(), sum.end(), [&](const auto& p) { return p.name == part.name; });
    if (it == sum.end()) sum.push_back(part);
    else it->bytes += part.bytes;
  }
}

int run(const InspectFlags& flags) {
  keep_freed_memory_for_reuse();  // every tile is decoded in turn (cli/batch_allocator.hpp)
  auto opened = store::Store::open(flags.store, {});
  if (!opened) { spdlog::error("cannot open store: {}", opened.error().message); return exit_code_for(opened.error()); }
  auto raw_meta = (*opened)->get(store::Database::meta, store::as_bytes(kMetaBuildKey));
  if (!raw_meta) { spdlog::error("{}", raw_meta.error().message); return exit_code_for(raw_meta.error()); }
  if (!raw_meta->has_value()) { spdlog::error("{} holds no build", flags.store); return kInvalidInput; }
  auto meta = StoreMeta::parse(std::string_view(reinterpret_cast<const char*>((*raw_meta)->data()), (*raw_meta)->size()));
  if (!meta) { spdlog::error("{}", meta.error().message); return exit_code_for(meta.error()); }

  std::map<std::string, MethodTotals> totals;
  Status corrupt;
  Status walked = (*opened)->for_each(store::Database::tiles, {}, [&](auto key, auto value) {
    auto tile_key = store::decode_tile_key(key);
    auto header = store::check_blob(value);
    if (!tile_key || !header) {
      corrupt = make_error(ErrorCode::corrupt_data, "a tile record fails its checks");
      return false;
    }
    auto& t = totals[store::method_name(tile_key->method)];
    ++t.tiles;
    t.blob_bytes += value.size();
    t.payload_bytes += header->raw_size;
    auto payload = store::decode_blob(value);
    if (!payload) {
      corrupt = payload.error();
      return false;
    }
    if (!t.undecodable) {
      auto decoded = decode_tile(tile_key->method, *payload);
      if (!decoded && decoded.error().code == ErrorCode::unsupported) {
        t.undecodable = true;
        t.parts.clear();
        t.counts.clear();
      } else if (!decoded) {
        corrupt = decoded.error();
        return false;
      } else {
        add_parts(t.parts, (*decoded)->size_breakdown());
        add_counts(t.counts, (*decoded)->structure_counts());
      }
    }
    return true;
  });
  if (!walked) { spdlog::error("{}", walked.error().message); return exit_code_for(walked.error()); }
  if (!corrupt) { spdlog::error("{}", corrupt.error().message); return kCorruptStore; }

  const double texels = double(meta->resolution) * meta->resolution;
  const double hit_texels = meta->build_stats.value("hit_texels", 0.0);
  nlohmann::json methods = nlohmann::json::object();
  for (auto& [name, t] : totals) {
    methods[name] = {{"tiles", t.tiles},
                     {"bytes", t.blob_bytes},
                     {"payload_bytes", t.payload_bytes},
                     {"bits_per_texel", 8.0 * double(t.blob_bytes) / texels},
                     {"bytes_per_nonempty_texel", hit_texels > 0 ? double(t.blob_bytes) / hit_texels : 0.0},
                     {"ratio_vs_float32_map", double(t.blob_bytes) / (4.0 * texels)}};
    for (const auto& c : t.counts) methods[name][c.group][c.name] = c.value;
    if (!t.parts.empty()) {
      nlohmann::json parts = nlohmann::json::array();
      for (const auto& part : t.parts)
        parts.push_back({{"name", part.name},
                         {"bytes", part.bytes},
                         {"fraction", t.payload_bytes > 0 ? double(part.bytes) / double(t.payload_bytes) : 0.0}});
      methods[name]["payload_parts"] = parts;
    }
  }
  nlohmann::json report = {{"meta", meta->to_json()}, {"methods", methods}};
  if (flags.json) {
    std::cout << report.dump(2) << "\n";
    return kOk;
  }
  std::printf("store %s: %u^2 texels, tiles of %u^2, %s, scene %s (%llu triangles)\n", flags.store.c_str(),
              meta->resolution, meta->tile_size, meta->complete ? "complete" : "INCOMPLETE",
              meta->scene_path.c_str(), (unsigned long long)meta->scene_triangles);
  std::printf("receivers %s, exit caps %s, entry slack %g (docs/receiver-contracts.md)\n",
              receiver_contract_name(meta->receivers), meta->exit_caps ? "on" : "off", meta->entry_slack);
  std::printf("%-8s %8s %14s %14s %10s %10s\n", "method", "tiles", "bytes", "payload", "bits/texel", "vs float32");
  for (auto& [name, t] : totals)
    std::printf("%-8s %8llu %14llu %14llu %10.4f %10.4f\n", name.c_str(), (unsigned long long)t.tiles,
                (unsigned long long)t.blob_bytes, (unsigned long long)t.payload_bytes,
                8.0 * double(t.blob_bytes) / texels, double(t.blob_bytes) / (4.0 * texels));
  for (auto& [name, t] : totals) {
    std::string group;
    for (const auto& c : t.counts) {
      if (c.group != group) std::printf("%s%-8s %s:", group.empty() ? "" : "\n", name.c_str(), c.group.c_str());
      std::printf("%s %llu %s", c.group == group ? "," : "", (unsigned long long)c.value, c.name.c_str());
      group = c.group;
    }
    if (!group.empty()) std::printf("\n");
  }
  for (auto& [name, t] : totals) {
    if (t.parts.empty()) continue;
    std::printf("%s payload parts:\n", name.c_str());
    for (const auto& part : t.parts)
      std::printf("  %-24s %14llu B %6.2f%%\n", part.name.c_str(), (unsigned long long)part.bytes,
                  t.payload_bytes > 0 ? 100.0 * double(part.bytes) / double(t.payload_bytes) : 0.0);
  }
  if (hit_texels > 0) std::printf("non-empty texels: %.0f (bytes per non-empty texel in --json)\n", hit_texels);
  return kOk;
}

}  // namespace

void add_inspect_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<InspectFlags>();
  CLI::App* cmd = app.add_subcommand("inspect", "Show what a store holds: meta, tiles and bytes per method");
  cmd->add_option("store", flags->store, "Store directory")->required();
  cmd->add_flag("--json", flags->json, "Print JSON");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
