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

#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "codec/dagmh_decoder.hpp"
#include "codec/decoded_tile.hpp"
#include "codec/mh_decoder.hpp"
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
  // MH family, from decoding every tile.
  bool hierarchical = false;
  uint64_t inner = 0, empty = 0, leaves = 0, blocks = 0, block_references = 0, skip_list_bytes = 0;
  unsigned levels = 0;
  // Payload parts summed over tiles, in the order the decoder names them.
  std::vector<DecodedTile::SizePart> parts;
  bool undecodable = false;  // no decoder in this build: no breakdown
  // DAG-MH counts.
  bool dag = false;
  uint64_t dag_nodes = 0, treelets = 0, values = 0, chunks = 0, representative_values = 0, quantized_values = 0,
           raw_values = 0;
};

void add_parts(std::vector<DecodedTile::SizePart>& sum, const std::vector<DecodedTile::SizePart>& parts) {
  for (const auto& part : parts) {
    auto it = std::find_if(sum.begin(), sum.end(), [&](const auto& p) { return p.name == part.name; });
    if (it == sum.end()) sum.push_back(part);
    else it->bytes += part.bytes;
  }
}

int run(const InspectFlags& flags) {
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
      } else if (!decoded) {
        corrupt = decoded.error();
        return false;
      } else {
        add_parts(t.parts, (*decoded)->size_breakdown());
      }
    }
    if (tile_key->method == store::Method::dagmh) {
      auto view = DagMhTileView::parse(*payload, DagMhParseOptions{0});
      if (!view) {
        corrupt = view.error();
        return false;
      }
      const DagMhStats& stats = view->stats();
      t.dag = true;
      t.dag_nodes += stats.dag_nodes;
      t.treelets += stats.treelets;
      t.values += stats.values;
      t.chunks += stats.chunks;
      t.representative_values += stats.representative_values;
      t.quantized_values += stats.quantized_values;
      t.raw_values += stats.raw_values;
    }
    if (tile_key->method == store::Method::mh || tile_key->method == store::Method::mmh) {
      auto view = MhTileView::parse(*payload);
      if (!view) {
        corrupt = view.error();
        return false;
      }
      const MhStats& stats = view->stats();
      t.hierarchical = true;
      t.inner += stats.inner_nodes;
      t.empty += stats.empty_nodes;
      t.leaves += stats.leaf_nodes;
      t.blocks += stats.blocks;
      t.block_references += stats.block_references;
      t.levels = std::max(t.levels, stats.levels);
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
    if (t.hierarchical)
      methods[name]["nodes"] = {{"inner", t.inner}, {"empty", t.empty}, {"leaf", t.leaves},
                                {"blocks", t.blocks}, {"block_references", t.block_references},
                                {"levels_in_tile", t.levels}};
    if (t.dag)
      methods[name]["dag"] = {{"dag_nodes", t.dag_nodes},
                              {"treelets", t.treelets},
                              {"values", t.values},
                              {"chunks", t.chunks},
                              {"representative_values", t.representative_values},
                              {"quantized_values", t.quantized_values},
                              {"raw_values", t.raw_values}};
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
  std::printf("receivers %s, exit caps %s (docs/receiver-contracts.md)\n", receiver_contract_name(meta->receivers),
              meta->exit_caps ? "on" : "off");
  std::printf("%-8s %8s %14s %14s %10s %10s\n", "method", "tiles", "bytes", "payload", "bits/texel", "vs float32");
  for (auto& [name, t] : totals)
    std::printf("%-8s %8llu %14llu %14llu %10.4f %10.4f\n", name.c_str(), (unsigned long long)t.tiles,
                (unsigned long long)t.blob_bytes, (unsigned long long)t.payload_bytes,
                8.0 * double(t.blob_bytes) / texels, double(t.blob_bytes) / (4.0 * texels));
  for (auto& [name, t] : totals)
    if (t.hierarchical)
      std::printf("%-8s nodes: %llu inner, %llu empty, %llu leaf; %llu child blocks (%llu references); %u levels per tile\n",
                  name.c_str(), (unsigned long long)t.inner, (unsigned long long)t.empty, (unsigned long long)t.leaves,
                  (unsigned long long)t.blocks, (unsigned long long)t.block_references, t.levels);
  for (auto& [name, t] : totals)
    if (t.dag)
      std::printf("%-8s %llu DAG nodes, %llu treelets; %llu values in %llu chunks: %llu representative, %llu "
                  "quantised, %llu raw\n",
                  name.c_str(), (unsigned long long)t.dag_nodes, (unsigned long long)t.treelets,
                  (unsigned long long)t.values, (unsigned long long)t.chunks,
                  (unsigned long long)t.representative_values, (unsigned long long)t.quantized_values,
                  (unsigned long long)t.raw_values);
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
