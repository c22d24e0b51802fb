// Receiver contracts (docs/receiver-contracts.md): both contracts lossless on real open scenes under
// verify's brute-force caps, recorded in the meta, part of the build identity, and verify catches a
// store whose intervals were not capped as its meta claims.
#include <gtest/gtest.h>

#include <thread>

#include <httplib.h>

#include "client/http_tile_source.hpp"
#include "client/shadow_map.hpp"
#include "codec/store_meta.hpp"
#include "server/server.hpp"
#include "store/lmdb_store.hpp"

#include "receiver_contracts_scenes.hpp"

namespace shadowtiles::testing {
namespace {

const ContractScene kHaus{"fzk_haus", "fzk_haus/fzk_haus.obj", "y"};
const ContractScene kBunny{"bunny", "bunny/stanford-bunny.obj", "y"};

TEST(ReceiverContracts, BothContractsAreLosslessOnOpenScenes) {
  for (const ContractScene& scene : {kHaus, kBunny}) {
    TempDir dir;
    // The open meshes as such (bunny is a nearly closed solid by default, tests/test_nearly_closed_meshes).
    auto anywhere = build_and_verify(scene, "anywhere", 512, dir.path() / "a", "--no-nearly-closed");
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

// The entry rule (--entry-slack-texels, docs/receiver-contracts.md; on at the bias by default under
// `surfaces`): verify's brute-force reference accepts every value; raw still stores the first hit
// (same bytes); DAG-MH shrinks; the meta records the slack; queries of the interval methods refuse a
// smaller bias, raw's accept it; `anywhere` refuses the flag.
TEST(ReceiverContracts, EntryRuleBuildsVerifyKeepRawAndRefuseSmallerBiases) {
  TempDir dir;
  auto without = build_and_verify(kHaus, "surfaces", 512, dir.path() / "s", "--entry-slack-texels 0");
  auto with = build_and_verify(kHaus, "surfaces", 512, dir.path() / "e");  // the default: slack = bias
  EXPECT_EQ(with["bytes_by_method"]["raw"], without["bytes_by_method"]["raw"]);
  EXPECT_LT(with["bytes_by_method"]["dagmh"].get<uint64_t>(), without["bytes_by_method"]["dagmh"].get<uint64_t>() * 9 / 10);
  std::printf("fzk_haus 512^2 surfaces dagmh bytes: %llu, with the entry rule %llu\n",
              (unsigned long long)without["bytes_by_method"]["dagmh"].get<uint64_t>(),
              (unsigned long long)with["bytes_by_method"]["dagmh"].get<uint64_t>());

  auto map = ShadowMap::open(dir.path() / "e");
  ASSERT_TRUE(map.ok()) << map.error().message;
  const StoreMeta& meta = (*map)->meta();
  EXPECT_NEAR(meta.entry_slack, meta.default_bias, 1e-12);
  std::string verified;
  ASSERT_EQ(run_stdout(cli_path().string() + " verify " + (dir.path() / "e").string() + " --json", &verified), 0);
  EXPECT_NEAR(nlohmann::json::parse(verified)["entry_slack"].get<double>(), meta.entry_slack, 1e-12);
  const Vec3 point = (*map)->meta().scene_bounds.min;
  EXPECT_TRUE((*map)->query(point, store::Method::dagmh).ok());  // the default bias
  auto refused = (*map)->query(point, store::Method::dagmh, meta.default_bias / 2);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::invalid_input);
  EXPECT_NE(refused.error().message.find("entry slack"), std::string::npos) << refused.error().message;
  EXPECT_FALSE((*map)->query_pcf(point, store::Method::mh, 3, meta.default_bias / 2).ok());
  EXPECT_TRUE((*map)->query(point, store::Method::raw, meta.default_bias / 2).ok());
  ShadowMap::BatchOptions options;
  options.bias = meta.default_bias / 2;
  ShadowMap::BatchAnswers answers;
  const std::vector<Vec3> points{point};
  EXPECT_FALSE((*map)->query_batch(points, store::Method::dagmh, options, answers).ok());
  EXPECT_TRUE((*map)->query_batch(points, store::Method::raw, options, answers).ok());

  std::string output;
  EXPECT_EQ(run_command(cli_path().string() + " build " + shared_scene(kHaus.file).string() +
                            " --up y --resolution 256 --tile 256 --method dagmh --receivers anywhere "
                            "--entry-slack-texels 2 --out " + (dir.path() / "a").string() + " 2>&1",
                        &output),
            2)
      << output;
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

TEST(ReceiverContracts, MetaWithoutTheFieldReadsAsAnywhereAndUnknownContractsAreRefused) {
  TempDir dir;
  const std::string cli = cli_path().string();
  ASSERT_EQ(run_command(cli + " build " + shared_scene(kHaus.file).string() +
                        " --up y --resolution 256 --tile 256 --method raw --receivers surfaces --out " +
                        (dir.path() / "s").string() + " 2>/dev/null"),
            0);
  auto map = ShadowMap::open(dir.path() / "s");
  ASSERT_TRUE(map.ok()) << map.error().message;
  nlohmann::json json = (*map)->meta().to_json();
  EXPECT_EQ(json["receivers"], "surfaces");
  json.erase("receivers");
  json.erase("exit_caps");
  json.erase("entry_slack");
  auto old = StoreMeta::from_json(json);  // a store built before contracts
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_EQ(old->receivers, ReceiverContract::anywhere);
  EXPECT_FALSE(old->exit_caps);
  json["receivers"] = "elsewhere";
  EXPECT_FALSE(StoreMeta::from_json(json).ok());
}

TEST(ReceiverContracts, ServerAnswersAndTheHttpClientNameTheContract) {
  TempDir dir;
  const std::string cli = cli_path().string();
  const auto store_dir = dir.path() / "s";
  ASSERT_EQ(run_command(cli + " build " + shared_scene(kHaus.file).string() +
                        " --up y --resolution 256 --tile 256 --method raw,dagmh --receivers surfaces --out " +
                        store_dir.string() + " 2>/dev/null"),
            0);
  server::ServerConfig config;
  config.port = 0;
  auto bound = server::Server::bind(config);
  ASSERT_TRUE(bound.ok()) << bound.error().message;
  std::unique_ptr<server::Server> server = std::move(*bound);
  ASSERT_TRUE(server->attach_store(store_dir).ok());
  std::thread runner([&] { EXPECT_TRUE(server->run().ok()); });
  httplib::Client client("127.0.0.1", server->port());
  client.set_read_timeout(20, 0);
  for (int i = 0; i < 200 && !client.Get("/healthz"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));

  auto meta = client.Get("/v1/meta");
  ASSERT_TRUE(meta && meta->status == 200);
  auto meta_json = nlohmann::json::parse(meta->body);
  EXPECT_EQ(meta_json["shadow"]["receivers"], "surfaces");
  EXPECT_EQ(meta_json["shadow"]["exit_caps"], true);
  // Built with the default: the entry rule on at the default query bias.
  EXPECT_GT(meta_json["shadow"]["entry_slack"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(meta_json["shadow"]["entry_slack"].get<double>(), meta_json["shadow"]["default_bias"].get<double>());
  auto point = client.Get("/v1/shadow?x=5&y=2&z=-5");
  ASSERT_TRUE(point && point->status == 200) << (point ? point->body : "no answer");
  EXPECT_EQ(nlohmann::json::parse(point->body)["receivers"], "surfaces");
  auto batch = client.Post("/v1/shadow", R"({"points": [[5, 2, -5], [0, 0, 0]]})", "application/json");
  ASSERT_TRUE(batch && batch->status == 200) << (batch ? batch->body : "no answer");
  EXPECT_EQ(nlohmann::json::parse(batch->body)["receivers"], "surfaces");
  std::string binary(12, '\0');
  auto binary_answer = client.Post("/v1/shadow", binary, "application/octet-stream");
  ASSERT_TRUE(binary_answer && binary_answer->status == 200);
  EXPECT_EQ(binary_answer->get_header_value("X-Shadow-Receivers"), "surfaces");
  // The streaming client learns the contract from the build record it fetches.
  auto source = HttpTileSource::open("http://127.0.0.1:" + std::to_string(server->port()), {});
  ASSERT_TRUE(source.ok()) << source.error().message;
  auto remote = ShadowMap::open(*source, {});
  ASSERT_TRUE(remote.ok()) << remote.error().message;
  EXPECT_EQ((*remote)->meta().receivers, ReceiverContract::surfaces);
  remote->reset();
  server->stop();
  runner.join();
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
