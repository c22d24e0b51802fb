// Shared by test_receiver_contracts(_long): build a real shared scene under a receiver contract with
// the CLI, then check it with `verify` (brute-force caps) and read its meta with `inspect`.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "testing_support.hpp"

namespace shadowtiles::testing {

struct ContractScene {
  const char* name;
  const char* file;  // under ../shared/scenes
  const char* up;
};

// The command's stdout alone (run_command appends 2>&1; the log goes to stderr): JSON reports parse.
inline int run_stdout(const std::string& command, std::string* output) {
  if (output) output->clear();
  return run_command("(" + command + " 2>/dev/null)", output);
}

inline nlohmann::json build_and_verify(const ContractScene& scene, const std::string& receivers, unsigned resolution,
                                       const std::filesystem::path& store, const std::string& extra = "") {
  const std::string cli = cli_path().string();
  std::string output;
  const std::string build = cli + " build " + shared_scene(scene.file).string() + " --up " + scene.up +
                            " --sun 135,45 --resolution " + std::to_string(resolution) + " --tile " +
                            std::to_string(std::min(resolution, 1024u)) +
                            " --method raw,mh,mmh,dagmh --receivers " + receivers + " --out " + store.string() +
                            " --json " + extra;
  EXPECT_EQ(run_stdout(build, &output), 0) << output;
  nlohmann::json summary = nlohmann::json::parse(output, nullptr, false);
  EXPECT_FALSE(summary.is_discarded()) << output;
  // Every texel of every method inside its capped interval, recomputed by the brute-force reference.
  EXPECT_EQ(run_stdout(cli + " verify " + store.string() + " --json", &output), 0) << output;
  nlohmann::json verify = nlohmann::json::parse(output, nullptr, false);
  EXPECT_FALSE(verify.is_discarded()) << output;
  if (!verify.is_discarded()) {
    EXPECT_EQ(verify["receivers"], receivers);
    EXPECT_EQ(verify["exit_caps"], extra.find("--no-exit-caps") == std::string::npos);
    for (const char* method : {"raw", "mh", "mmh", "dagmh"}) {
      EXPECT_EQ(verify[method]["outside"].get<uint64_t>(), 0u) << scene.name << " " << receivers << " " << method;
      EXPECT_EQ(verify[method]["wrong_answers"].get<uint64_t>(), 0u) << scene.name << " " << receivers << " " << method;
      EXPECT_EQ(verify[method]["texels"].get<uint64_t>(), uint64_t(resolution) * resolution);
    }
  }
  return summary;
}

}  // namespace shadowtiles::testing
