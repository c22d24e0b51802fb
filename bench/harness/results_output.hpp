// Results output of `shadowtiles bench`: results.json (the whole document), results.csv (one line
// per row; columns = every key of the rows in first-seen order, so a method lacking a figure leaves
// an empty cell) and the per-scene table printed to stdout.
// Errors: io_error when a file cannot be written.
// Thread safety: pure functions apart from the files they write.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/result.hpp"

namespace shadowtiles::bench {

// Column names of `rows` in first-seen order.
std::vector<std::string> csv_columns(const nlohmann::ordered_json& rows);
std::string to_csv(const nlohmann::ordered_json& rows);

// Writes OUT/results.json and OUT/results.csv.
Status write_results(const std::filesystem::path& out_dir, const nlohmann::ordered_json& document);

// A fixed-width table of one scene's rows (sizes, error, PCF error, lookup rates).
std::string format_scene_table(const std::string& scene, const nlohmann::ordered_json& rows);

}  // namespace shadowtiles::bench
