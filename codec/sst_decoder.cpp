#include "codec/sst_decoder.hpp"

#include <string>
#include <vector>

#include "codec/sst_format.hpp"

#include "codec/sst_tile_view.hpp"

namespace shadowtiles {
namespace {

// The view points into the owned payload copy.
class SstDecodedTile final : public DecodedTile {
 public:
  static Result<std::shared_ptr<const DecodedTile>> make(std::span<const uint8_t> payload) {
    auto tile = std::shared_ptr<SstDecodedTile>(new SstDecodedTile(payload));
    auto view = SstTileView::parse(tile->payload_);
    if (!view) return view.error();
    tile->view_ = std::move(*view);
    return std::shared_ptr<const DecodedTile>(std::move(tile));
  }
  uint32_t size() const override { return view_.size(); }
  float value(uint32_t u, uint32_t v, unsigned max_level) const override { return view_.lookup(u, v, max_level); }
  size_t memory_bytes() const override { return payload_.size() + sizeof(*this); }
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const override {
    return view_.lit_count(u0, v0, kw, kh, threshold);
  }
  // Names are fixed (inspect sums parts by name over tiles); counts are in SstTileView::stats().
  std::vector<SizePart> size_breakdown() const override {
    const SstStats& s = view_.stats();
    return {{"header", s.header_bytes},
            {"block grid", s.grid_bytes},
            {"block offset widths", s.block_width_bytes},
            {"internal nodes", s.internal_bytes},
            {"one leaves", s.one_leaves},
            {"constant leaves", s.constant_leaves * sst_format::kConstantBytes},
            {"plane leaves", s.plane_leaves * sst_format::kPlaneBytes},
            {"dense leaves", s.dense_bytes}};
  }
  const SstTileView& view() const { return view_; }

 private:
  explicit SstDecodedTile(std::span<const uint8_t> payload) : payload_(payload.begin(), payload.end()) {}
  std::vector<uint8_t> payload_;
  SstTileView view_;
};

}  // namespace

Result<std::shared_ptr<const DecodedTile>> decode_sst_tile(std::span<const uint8_t> payload) {
  return SstDecodedTile::make(payload);
}

}  // namespace shadowtiles
