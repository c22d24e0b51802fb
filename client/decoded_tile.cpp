#include "client/decoded_tile.hpp"

#include "client/raw_tile.hpp"

namespace shadowtiles {
namespace {

class RawDecodedTile final : public DecodedTile {
 public:
  explicit RawDecodedTile(RawTileView view) : view_(std::move(view)) {}
  uint32_t size() const override { return view_.size(); }
  float value(uint32_t u, uint32_t v, unsigned) const override { return view_.value(u, v); }
  size_t memory_bytes() const override { return view_.memory_bytes(); }

 private:
  RawTileView view_;
};

}  // namespace

Result<std::shared_ptr<const DecodedTile>> decode_tile(store::Method method, std::span<const uint8_t> payload) {
  switch (method) {
    case store::Method::raw: {
      auto view = RawTileView::parse(payload);
      if (!view) return view.error();
      return std::shared_ptr<const DecodedTile>(std::make_shared<RawDecodedTile>(std::move(*view)));
    }
    default:
      return make_error(ErrorCode::unsupported,
                        std::string("no decoder for method '") + store::method_name(method) + "'");
  }
}

}  // namespace shadowtiles
