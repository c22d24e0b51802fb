#include "builder/method_encoders.hpp"

#include <array>
#include <mutex>
#include <string>

#include "builder/cpvs_encoder.hpp"
#include "builder/dagmh_encoder.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mmh_merger.hpp"
#include "builder/sst_encoder.hpp"
#include "codec/raw_tile.hpp"

namespace shadowtiles {
namespace {

using store::Method;

Result<EncodedBytes> encode_raw(TileEncodeInput& input) {
  const TileIntervals& intervals = input.intervals();
  std::vector<float> lower(intervals.texels.size());
  for (size_t i = 0; i < lower.size(); ++i) lower[i] = intervals.texels[i].lower;
  return EncodedBytes{encode_raw_tile(intervals.size, lower), 0};
}

Result<EncodedBytes> encode_mh_method(TileEncodeInput& input) {
  auto encoded = input.mh_encoded();
  if (!encoded) return encoded.error();
  return **encoded;
}

Result<EncodedBytes> encode_mmh_method(TileEncodeInput& input) {
  auto mh = input.mh();
  if (!mh) return mh.error();
  // Where no block can merge (most full-depth tiles of open meshes under `anywhere`), MMH is MH byte
  // for byte: the merge, its renumbering and a second encode would only say so.
  if (mmh_merge_finds_nothing(**mh)) {
    auto encoded = input.mh_encoded();
    if (!encoded) return encoded.error();
    return **encoded;
  }
  auto merged = merge_mmh(**mh);
  if (!merged) return merged.error();
  auto bytes = encode_mh(*merged);
  if (!bytes) return bytes.error();
  return EncodedBytes{std::move(*bytes), sbe16a_reference_bytes(*merged)};
}

Result<EncodedBytes> encode_dagmh_method(TileEncodeInput& input) {
  auto mh = input.mh();
  if (!mh) return mh.error();
  auto bytes = encode_dagmh(**mh);
  if (!bytes) return bytes.error();
  return EncodedBytes{std::move(*bytes), 0};
}

Result<EncodedBytes> encode_cpvs_method(TileEncodeInput& input) {
  auto bytes = encode_cpvs_tile(input.interval_method_intervals(), input.options().map_resolution);
  if (!bytes) return bytes.error();
  return EncodedBytes{std::move(*bytes), 0};
}

Result<EncodedBytes> encode_sst_method(TileEncodeInput& input) {
  auto bytes = encode_sst_tile(input.intervals());
  if (!bytes) return bytes.error();
  return EncodedBytes{std::move(*bytes), 0};
}

Result<std::vector<uint8_t>> mh_top_tree(const TileIntervals& roots, unsigned skip_level) {
  auto top = build_mh(roots);
  if (!top) return top.error();
  MhEncodeOptions options;
  options.embed_skip_list = true;
  options.skip_level = skip_level;
  return encode_mh(*top, options);
}

Result<std::vector<uint8_t>> mmh_top_tree(const TileIntervals& roots, unsigned skip_level) {
  auto top = build_mh(roots);
  if (!top) return top.error();
  auto merged = merge_mmh(*top);
  if (!merged) return merged.error();
  MhEncodeOptions options;
  options.embed_skip_list = true;
  options.skip_level = skip_level;
  return encode_mh(*merged, options);
}

// DAG-MH embeds its own skip list (DagMhOptions defaults, as the tiles).
Result<std::vector<uint8_t>> dagmh_top_tree(const TileIntervals& roots, unsigned) {
  auto top = build_mh(roots);
  if (!top) return top.error();
  return encode_dagmh(*top);
}

struct EncoderTable {
  std::array<std::optional<MethodEncoder>, 256> by_byte{};
  std::mutex writers;
  EncoderTable() {
    // The built-in methods: one line each.
    by_byte[uint8_t(Method::raw)] = MethodEncoder{encode_raw, nullptr, nullptr};
    by_byte[uint8_t(Method::mh)] = MethodEncoder{encode_mh_method, nullptr, mh_top_tree};
    by_byte[uint8_t(Method::mmh)] = MethodEncoder{encode_mmh_method, nullptr, mmh_top_tree};
    by_byte[uint8_t(Method::dagmh)] = MethodEncoder{encode_dagmh_method, nullptr, dagmh_top_tree};
    by_byte[uint8_t(Method::cpvs)] = MethodEncoder{encode_cpvs_method, cpvs_encoder_available, nullptr};
    by_byte[uint8_t(Method::sst)] = MethodEncoder{encode_sst_method, sst_encoder_available, nullptr};
  }
};

EncoderTable& table() {
  static EncoderTable t;
  return t;
}

}  // namespace

const TileIntervals& TileEncodeInput::interval_method_intervals() {
  if (intervals_.entry_lower.empty()) return intervals_;
  if (!entry_applied_) {
    entry_applied_ = intervals_;
    apply_entry_rule(*entry_applied_);
  }
  return *entry_applied_;
}

Result<const MhHierarchy*> TileEncodeInput::mh() {
  if (!mh_) {
    MhBuildOptions build_options;
    build_options.construction = options_.construction;
    // The renderer's intervals: build_mh applies their entry-rule bounds as it reads them.
    auto built = build_mh(intervals_, build_options);
    if (!built) return built.error();
    mh_ = std::move(*built);
  }
  return &*mh_;
}

Result<const EncodedBytes*> TileEncodeInput::mh_encoded() {
  if (!mh_encoded_) {
    auto tree = mh();
    if (!tree) return tree.error();
    auto bytes = encode_mh(**tree);
    if (!bytes) return bytes.error();
    mh_encoded_ = EncodedBytes{std::move(*bytes), sbe16a_reference_bytes(**tree)};
  }
  return &*mh_encoded_;
}

const MethodEncoder* find_encoder(store::Method method) {
  const auto& entry = table().by_byte[uint8_t(method)];
  return entry ? &*entry : nullptr;
}

Status register_encoder(store::Method method, const MethodEncoder& encoder) {
  if (!store::method_from_byte(uint8_t(method)))
    return make_error(ErrorCode::invalid_input,
                      "register_encoder: method byte " + std::to_string(uint8_t(method)) + " is not registered");
  EncoderTable& t = table();
  std::lock_guard lock(t.writers);
  const std::string name = store::method_name(method);
  if (t.by_byte[uint8_t(method)])
    return make_error(ErrorCode::invalid_input, "register_encoder: '" + name + "' already has an encoder");
  if (!encoder.encode) return make_error(ErrorCode::invalid_input, "register_encoder: '" + name + "' has no encode");
  if (bool(encoder.encode_top_tree) != store::method_properties(method).has_top_tree)
    return make_error(ErrorCode::invalid_input,
                      "register_encoder: '" + name + "': a top-tree encoder exactly when has_top_tree");
  t.by_byte[uint8_t(method)] = encoder;
  return {};
}

}  // namespace shadowtiles
