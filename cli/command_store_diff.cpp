// `shadowtiles store-diff A B`: do two stores hold the same build? Every entry of tiles, tileinfo,
// progress and top byte for byte, and the meta equal except build statistics that depend on the
// run (timings, resumes); the size statistics must agree. Exit 0 same, 3 different (first
// difference printed), 1/4 when a store cannot be read. Used to check a merge against a
// one-machine build (tests/slurm_array_test.sh, docs/scale-out.md).
#include <cstdio>

#include <spdlog/spdlog.h>

#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "codec/store_meta.hpp"
#include "store/lmdb_store.hpp"

namespace shadowtiles::cli {
namespace {

using Bytes = std::vector<uint8_t>;

Result<std::optional<std::string>> first_difference(const store::Store& a, const store::Store& b, store::Database db) {
  auto na = a.entry_count(db), nb = b.entry_count(db);
  if (!na) return na.error();
  if (!nb) return nb.error();
  const std::string name = store::database_name(db);
  if (*na != *nb)
    return std::optional<std::string>(name + ": " + std::to_string(*na) + " entries vs " + std::to_string(*nb));
  Bytes after;
  std::optional<std::string> difference;
  for (;;) {
    std::vector<std::pair<Bytes, Bytes>> chunk;
    if (Status s = a.for_each_after(db, after, [&](std::span<const uint8_t> k, std::span<const uint8_t> v) {
          chunk.emplace_back(Bytes(k.begin(), k.end()), Bytes(v.begin(), v.end()));
          return chunk.size() < 512;
        });
        !s)
      return s.error();
    if (chunk.empty()) return difference;
    for (auto& [key, value] : chunk) {
      auto other = b.get(db, key);
      if (!other) return other.error();
      if (!other->has_value()) return std::optional<std::string>(name + ": a key of the first store is missing in the second");
      if (**other != value) return std::optional<std::string>(name + ": values differ under a key");
    }
    after = chunk.back().first;
  }
}

int run(const std::string& path_a, const std::string& path_b) {
  store::Store::Options options;
  auto a = store::Store::open(path_a, options);
  if (!a) { spdlog::error("{}", a.error().message); return exit_code_for(a.error()); }
  auto b = store::Store::open(path_b, options);
  if (!b) { spdlog::error("{}", b.error().message); return exit_code_for(b.error()); }
  for (auto db : {store::Database::tiles, store::Database::tileinfo, store::Database::preview, store::Database::progress,
                  store::Database::top}) {
    auto difference = first_difference(**a, **b, db);
    if (!difference) { spdlog::error("{}", difference.error().message); return exit_code_for(difference.error()); }
    if (*difference) { std::printf("different: %s\n", (*difference)->c_str()); return kCheckFailed; }
  }
  auto meta_of = [](const store::Store& s) -> Result<StoreMeta> {
    auto text = s.get(store::Database::meta, store::as_bytes(kMetaBuildKey));
    if (!text) return text.error();
    if (!text->has_value()) return make_error(ErrorCode::not_found, "no build meta");
    return StoreMeta::parse(std::string((*text)->begin(), (*text)->end()));
  };
  auto ma = meta_of(**a), mb = meta_of(**b);
  if (!ma || !mb) { spdlog::error("meta: {}", (ma ? mb.error() : ma.error()).message); return kCorruptStore; }
  for (const char* key : {"bytes_by_method", "payload_bytes_by_method", "top_bytes_by_method"})
    if (ma->build_stats.value(key, nlohmann::json()) != mb->build_stats.value(key, nlohmann::json())) {
      std::printf("different: build_stats.%s\n", key);
      return kCheckFailed;
    }
  ma->build_stats = mb->build_stats = nlohmann::json::object();
  if (ma->to_json() != mb->to_json()) {
    std::printf("different: meta\n  %s\n  %s\n", ma->to_json().dump().c_str(), mb->to_json().dump().c_str());
    return kCheckFailed;
  }
  std::printf("same build: tiles, tileinfo, preview, progress, top byte-identical; meta equal except timings\n");
  return kOk;
}

}  // namespace

void add_store_diff_command(CLI::App& app, int& exit_code) {
  auto paths = std::make_shared<std::pair<std::string, std::string>>();
  CLI::App* cmd = app.add_subcommand("store-diff", "Check that two stores hold the same build (e.g. a merge vs a one-machine build)");
  cmd->add_option("a", paths->first, "First store")->required();
  cmd->add_option("b", paths->second, "Second store")->required();
  cmd->callback([paths, &exit_code] { exit_code = run(paths->first, paths->second); });
}

}  // namespace shadowtiles::cli
