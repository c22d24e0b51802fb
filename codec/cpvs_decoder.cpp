#include "codec/cpvs_decoder.hpp"

#include <cmath>
#include <limits>

#include "codec/cpvs_tile_view.hpp"

namespace shadowtiles {
namespace {

// Owns the payload; the view points into it.
class CpvsDecodedTile final : public DecodedTile {
 public:
  static Result<std::shared_ptr<const DecodedTile>> make(std::span<const uint8_t> payload) {
    auto tile = std::shared_ptr<CpvsDecodedTile>(new CpvsDecodedTile(payload));
    auto view = CpvsTileView::parse(tile->payload_);
    if (!view) return view.error();
    tile->view_ = std::move(*view);
    return std::shared_ptr<const DecodedTile>(std::move(tile));
  }
  uint32_t size() const override { return view_.size(); }
  // Start of the first shadowed step: a depth-map stand-in for reports; lit() is the answer.
  float value(uint32_t u, uint32_t v, unsigned) const override {
    uint32_t step = view_.first_shadowed_step(u, v);
    if (step >= view_.depth_steps()) return std::numeric_limits<float>::infinity();
    return float(double(step) / double(view_.depth_steps()));
  }
  bool lit(uint32_t u, uint32_t v, float threshold, unsigned) const override { return view_.lit(u, v, threshold); }
  // A point query's answer in one descent to the receiver's voxel. Its value is the bound of that
  // voxel's depth step that the answer proves (lit: the step's far end, +inf past the last step;
  // shadowed: just before its near end), so `threshold <= value` iff lit, as for depth maps. The
  // column's first shadowed step (value()) would cost a search of the column: 3-4x the lookup.
  Sample sample(uint32_t u, uint32_t v, float threshold, unsigned) const override {
    const int64_t step = cpvs::depth_step(threshold, view_.depth_steps());
    if (step == cpvs::kLitBeforeEverything) return {0.0f, true};
    const double steps = double(view_.depth_steps());
    if (view_.lit_at_step(u, v, uint32_t(step))) {
      if (uint32_t(step) + 1 == view_.depth_steps()) return {std::numeric_limits<float>::infinity(), true};
      return {float(double(step + 1) / steps), true};  // exact: N is a power of two, step < 2^20
    }
    return {std::nextafter(float(double(step) / steps), -std::numeric_limits<float>::infinity()), false};
  }
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const override {
    return view_.lit_count(u0, v0, kw, kh, threshold);
  }
  size_t memory_bytes() const override { return payload_.size() + sizeof(*this) + view_.derived_bytes(); }
  std::vector<SizePart> size_breakdown() const override {
    const auto& s = view_.stats();
    return {{"cpvs header", s.header_bytes}, {"cpvs nodes", s.node_bytes}, {"cpvs leaf masks", s.leaf_bytes}};
  }

 private:
  explicit CpvsDecodedTile(std::span<const uint8_t> payload) : payload_(payload.begin(), payload.end()) {}
  std::vector<uint8_t> payload_;
  CpvsTileView view_;
};

}  // namespace

Result<std::shared_ptr<const DecodedTile>> decode_cpvs_tile(std::span<const uint8_t> payload) {
  return CpvsDecodedTile::make(payload);
}

}  // namespace shadowtiles
