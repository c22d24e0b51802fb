// Receiver contracts (docs/receiver-contracts.md): both contracts lossless on real open scenes under
// verify's brute-force caps, recorded in the meta, part of the build identity, and verify catches a
// store whose intervals were not capped as its meta claims.
#include <gtest/gtest.h>

#include "codec/store_meta.hpp"
#include "store/lmdb_store.hpp"

#include "receiver_contracts_scenes.hpp"

namespace shadowtiles::testing {
namespace {

const ContractScene kHaus{"fzk_haus", "fzk_haus/fzk_haus.obj", "y"};
const ContractScene kBunny{"bunny", "bunny/stanford-bunny.obj", "y"};

TEST(ReceiverContracts, BothContractsAreLosslessOnOpenScenes) {
  for (const ContractScene& scene : {kHaus, kBunny}) {
    TempDir dir;
    auto anywhere = build_and_verify(scene, "anywhere", 512, dir.path() / "a");
    auto surfaces = build_and_verify(scene, "surfaces", 512, dir.path() / "s");
    // The point of the contract: open meshes get intervals, so DAG-MH shrinks.
    const auto a = anywhere["bytes_by_method"]["dagmh"].get<uint64_t>();
    const auto s = surfaces["bytes_by_method"]["dagmh"].get<uint64_t>();
    EXPECT_LT(s, a) << scene.name;
    EXPECT_GT(surfaces["exit_texels"].get<uint64_t>(), anywhere["exit_texels"].get<uint64_t>()) << scene.name;
    std::printf("%s 512^2 dagmh bytes: anywhere %llu, surfaces %llu\n", scene.name, (unsigned long long)a,
                (unsigned long long)s);
  }
}

TEST(ReceiverContracts, TexelCentreIntervalsVerifyWithoutCaps) {
  TempDir dir;
  build_and_verify(kHaus, "surfaces", 256, dir.path() / "s", "--no-exit-caps");
}

TEST(ReceiverContracts, ContractIsInTheMetaAndTheBuildIdentity) {
  TempDir dir;
  const std::string cli = cli_path().string();
  const std::string base = cli + " build " + shared_scene(kHaus.file).string() +
                           " --up y --resolution 256 --tile 256 --method raw,mh --out " + (dir.path() / "s").string();
  ASSERT_EQ(run_command(base + " --receivers surfaces 2>/dev/null"), 0);
  std::string output;
  ASSERT_EQ(run_stdout(cli + " inspect " + (dir.path() / "s").string() + " --json", &output), 0);
  auto report = nlohmann::json::parse(output);
  EXPECT_EQ(report["meta"]["receivers"], "surfaces");
  EXPECT_EQ(report["meta"]["exit_caps"], true);
  // Resuming with the other contract is another build: refused (invalid input) without --overwrite.
  EXPECT_EQ(run_command(base + " --receivers anywhere 2>&1", &output), 2) << output;
  EXPECT_NE(output.find("different build"), std::string::npos) << output;
  EXPECT_EQ(run_command(base + " --receivers elsewhere 2>&1", &output), 2) << output;
}

// Rewrites the store's meta field `exit_caps` (the record is JSON under key "build").
void set_meta_exit_caps(const std::filesystem::path& store_path, bool caps) {
  store::Store::Options options;
  options.mode = store::Store::Mode::read_write;
  auto opened = store::Store::open(store_path, options);
  ASSERT_TRUE(opened.ok());
  store::Store& db = **opened;
  auto raw = db.get(store::Database::meta, store::as_bytes(kMetaBuildKey));
  ASSERT_TRUE(raw.ok() && raw->has_value());
  auto meta = nlohmann::json::parse(std::string(reinterpret_cast<const char*>((*raw)->data()), (*raw)->size()));
  meta["exit_caps"] = caps;
  const std::string text = meta.dump();
  const std::string key = kMetaBuildKey;
  std::vector<store::Store::Put> puts{{store::Database::meta, std::vector<uint8_t>(key.begin(), key.end()),
                                       std::vector<uint8_t>(text.begin(), text.end())}};
  ASSERT_TRUE(db.write(puts).ok());
}

TEST(ReceiverContracts, VerifyCatchesUncappedIntervalsUnderACappedMeta) {
  // Built with the texel-centre rule, but claiming caps: the reference caps must find values above
  // them (the off-centre receivers the caps protect), or verify would prove nothing.
  TempDir dir;
  const std::string cli = cli_path().string();
  const auto store = dir.path() / "s";
  ASSERT_EQ(run_command(cli + " build " + shared_scene(kHaus.file).string() +
                        " --up y --resolution 512 --tile 512 --method raw,mh --receivers surfaces --no-exit-caps --out " +
                        store.string() + " 2>/dev/null"),
            0);
  set_meta_exit_caps(store, true);
  std::string output;
  EXPECT_EQ(run_stdout(cli + " verify " + store.string() + " --json", &output), 3) << output;
  auto report = nlohmann::json::parse(output, nullptr, false);
  ASSERT_FALSE(report.is_discarded()) << output;
  EXPECT_EQ(report["raw"]["outside"].get<uint64_t>(), 0u);
  EXPECT_GT(report["mh"]["outside"].get<uint64_t>(), 0u);
}

}  // namespace
}  // namespace shadowtiles::testing
