// The method table (store/method.hpp, codec/method_decoders.hpp, builder/method_encoders.hpp): the
// built-in rows say what docs/architecture.md §14 says, registration refuses clashes, and a toy
// method registered only here builds, stores, decodes, answers queries and verifies on a real scene
// through the tables, with no line of it outside this file.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <mutex>

#include "builder/build_job.hpp"
#include "builder/method_encoders.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "builder/tile_encoder.hpp"
#include "client/shadow_map.hpp"
#include "codec/method_decoders.hpp"
#include "common/byte_order.hpp"
#include "store/blob.hpp"
#include "store/lmdb_store.hpp"
#include "store/tile_key.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/testing_support.hpp"
#include "tests/verified_build.hpp"

namespace shadowtiles {
namespace {

using store::Method;

// The toy: per texel, the interval's upper bound when finite, else its lower one (any value inside
// [lower, upper] is lossless). Payload: size u32 LE, then size^2 f32 LE.
constexpr Method kToy = Method(200);

float toy_value(const DepthInterval& d) { return std::isfinite(d.upper) ? d.upper : d.lower; }

class ToyTile final : public DecodedTile {
 public:
  ToyTile(uint32_t size, std::vector<float> values) : size_(size), values_(std::move(values)) {}
  uint32_t size() const override { return size_; }
  float value(uint32_t u, uint32_t v, unsigned) const override { return values_[size_t(v) * size_ + u]; }
  size_t memory_bytes() const override { return values_.size() * sizeof(float) + sizeof(*this); }

 private:
  uint32_t size_;
  std::vector<float> values_;
};

Result<std::shared_ptr<const DecodedTile>> decode_toy(std::span<const uint8_t> payload) {
  if (payload.size() < 4) return make_error(ErrorCode::corrupt_data, "toy: short payload");
  const uint32_t size = bytes::load_le<uint32_t>(payload.data());
  if (size == 0 || size > 65536 || payload.size() != 4 + uint64_t(size) * size * 4)
    return make_error(ErrorCode::corrupt_data, "toy: payload size does not match its side");
  std::vector<float> values(size_t(size) * size);
  for (size_t i = 0; i < values.size(); ++i) {
    values[i] = bytes::load_f32(payload.data() + 4 + 4 * i);
    if (!std::isfinite(values[i])) return make_error(ErrorCode::corrupt_data, "toy: value not finite");
  }
  return std::shared_ptr<const DecodedTile>(std::make_shared<ToyTile>(size, std::move(values)));
}

Result<EncodedBytes> encode_toy(TileEncodeInput& input) {
  const TileIntervals& intervals = input.intervals();
  EncodedBytes out;
  out.payload.resize(4 + intervals.texels.size() * 4);
  bytes::store_le<uint32_t>(out.payload.data(), intervals.size);
  for (size_t i = 0; i < intervals.texels.size(); ++i)
    bytes::store_le<uint32_t>(out.payload.data() + 4 + 4 * i, std::bit_cast<uint32_t>(toy_value(intervals.texels[i])));
  return out;
}

// The one registration a new method needs (each line a table of one layer).
void register_toy_method() {
  static std::once_flag once;
  std::call_once(once, [] {
    ASSERT_TRUE(store::register_method({kToy, "toy", {.interval_exact = true}, "", "tests/test_method_registry.cpp"}));
    ASSERT_TRUE(register_decoder(kToy, decode_toy));
    ASSERT_TRUE(register_encoder(kToy, MethodEncoder{encode_toy, nullptr, nullptr}));
  });
}

TEST(MethodRegistry, BuiltInRowsMatchTheArchitectureTable) {
  struct Row {
    Method id;
    const char* name;
    bool hierarchical, interval_exact, top_tree, visibility, reference;
  };
  const Row rows[] = {{Method::raw, "raw", false, true, false, false, true},
                      {Method::mh, "mh", true, true, true, false, false},
                      {Method::mmh, "mmh", true, true, true, false, false},
                      {Method::dagmh, "dagmh", true, true, true, false, false},
                      {Method::cpvs, "cpvs", false, false, false, true, false},
                      {Method::sst, "sst", false, true, false, false, false}};
  for (const Row& r : rows) {
    SCOPED_TRACE(r.name);
    const store::MethodInfo& info = store::method_info(r.id);
    EXPECT_EQ(info.name, r.name);
    EXPECT_EQ(store::parse_method(r.name).value(), r.id);
    EXPECT_EQ(info.properties.hierarchical, r.hierarchical);
    EXPECT_EQ(info.properties.interval_exact, r.interval_exact);
    EXPECT_EQ(info.properties.has_top_tree, r.top_tree);
    EXPECT_EQ(info.properties.stores_visibility, r.visibility);
    EXPECT_EQ(info.properties.reference, r.reference);
    EXPECT_EQ(info.lossy_by.empty(), r.id != Method::cpvs);
    EXPECT_NE(find_decoder(r.id), nullptr);
    const MethodEncoder* encoder = find_encoder(r.id);
    ASSERT_NE(encoder, nullptr);
    EXPECT_EQ(encoder->encode_top_tree != nullptr, r.top_tree);
  }
}

TEST(MethodRegistry, RegistrationRefusesClashesAndBadNames) {
  register_toy_method();
  EXPECT_FALSE(store::register_method({Method::mh, "other", {}, "", ""})) << "taken byte";
  EXPECT_FALSE(store::register_method({Method(201), "mh", {}, "", ""})) << "taken name";
  EXPECT_FALSE(store::register_method({Method(0), "zero", {}, "", ""})) << "byte 0";
  EXPECT_FALSE(store::register_method({Method(202), "Bad-Name", {}, "", ""}));
  EXPECT_FALSE(store::register_method({Method(203), "", {}, "", ""}));
  EXPECT_FALSE(store::method_from_byte(201).ok()) << "a refused registration leaves nothing behind";
  EXPECT_FALSE(register_decoder(kToy, decode_toy)) << "second decoder";
  EXPECT_FALSE(register_decoder(Method(204), decode_toy)) << "decoder for an unregistered byte";
  EXPECT_FALSE(register_encoder(kToy, MethodEncoder{encode_toy, nullptr, nullptr})) << "second encoder";
  EXPECT_FALSE(register_encoder(Method(204), MethodEncoder{encode_toy, nullptr, nullptr}));
  auto unknown = decode_tile(Method(205), std::span<const uint8_t>{});
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::unsupported);
}

TEST(MethodRegistry, ToyMethodNamedAtTheOuterInterfaces) {
  register_toy_method();
  EXPECT_EQ(store::parse_method("toy").value(), kToy);
  EXPECT_STREQ(store::method_name(kToy), "toy");
  auto list = store::parse_method_list("raw, toy");
  ASSERT_TRUE(list.ok());
  EXPECT_EQ(list->back(), kToy);
  EXPECT_TRUE(builder_supports(kToy));
  // Keys and blobs carry its byte.
  auto key = store::decode_tile_key(store::encode_tile_key({kToy, 3, 1, 2}));
  ASSERT_TRUE(key.ok());
  EXPECT_EQ(key->method, kToy);
}

TEST(MethodRegistry, ToyMethodBuildsStoresDecodesAndVerifiesOnARealScene) {
  register_toy_method();
  testing::TempDir dir;
  const BuildConfig config =
      testing::shared_scene_config({"fzk_haus/fzk_haus.obj", UpAxis::y, false}, dir.path() / "s", 256, 64,
                                   {Method::raw, kToy}, 135, 40);
  // Every texel decodes inside its interval: verify re-renders the intervals and checks all of them.
  auto verified = testing::build_and_verify_every_texel(config, {Method::raw, kToy});
  ASSERT_TRUE(verified.has_value());
  EXPECT_GT(verified->stats["bytes_by_method"]["toy"].get<uint64_t>(), 0u);

  auto map = ShadowMap::open(config.store_path);
  ASSERT_TRUE(map.ok()) << map.error().message;
  ASSERT_TRUE((*map)->meta().has_method(kToy));
  auto scene = load_scene(config.scene_path, config.load);
  ASSERT_TRUE(scene.ok());

  // Queries through ShadowMap: on surface receivers the toy answers as raw does (both lossless).
  auto receivers = sample_receivers(*scene, 2000, 7);
  size_t same = 0, answered = 0;
  for (const Receiver& r : receivers) {
    auto a = (*map)->query(r.position, Method::raw);
    auto b = (*map)->query(r.position, kToy);
    ASSERT_TRUE(a.ok() && b.ok());
    ++answered;
    same += a->lit == b->lit;
  }
  EXPECT_EQ(answered, receivers.size());
  EXPECT_GE(double(same), 0.99 * double(answered)) << "toy and raw disagree on " << answered - same << " receivers";

  // A stored toy blob, flipped, is an error, never an answer.
  const store::Store* store = (*map)->local_store();  // one LMDB handle per process
  ASSERT_NE(store, nullptr);
  size_t toy_tiles = 0;
  ASSERT_TRUE(store->for_each(store::Database::tiles, {}, [&](std::span<const uint8_t> k, std::span<const uint8_t> v) {
    auto tile_key = store::decode_tile_key(k);
    if (!tile_key || tile_key->method != kToy) return true;
    ++toy_tiles;
    auto payload = store::decode_blob(v);
    EXPECT_TRUE(payload.ok());
    if (payload.ok()) {
      EXPECT_TRUE(decode_tile(kToy, *payload).ok());
    }
    std::vector<uint8_t> bad(v.begin(), v.end());
    bad[bad.size() / 2] ^= 0x10;
    EXPECT_FALSE(store::decode_blob(bad).ok());
    return true;
  }));
  EXPECT_GT(toy_tiles, 0u);
}

}  // namespace
}  // namespace shadowtiles
