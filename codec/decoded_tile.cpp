#include "codec/decoded_tile.hpp"

#include <string>

#include "codec/dagmh_decoder.hpp"
#include "codec/method_decoders.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/raw_tile.hpp"

namespace shadowtiles {
namespace {

class RawDecodedTile final : public DecodedTile {
 public:
  explicit RawDecodedTile(RawTileView view) : view_(std::move(view)) {}
  uint32_t size() const override { return view_.size(); }
  float value(uint32_t u, uint32_t v, unsigned) const override { return view_.value(u, v); }
  size_t memory_bytes() const override { return view_.memory_bytes(); }
  // Not the base class's loop of virtual lit() calls: a raw PCF box is a few array reads.
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const override {
    return view_.lit_count(u0, v0, kw, kh, threshold);
  }
  bool lit(uint32_t u, uint32_t v, float threshold, unsigned) const override { return threshold <= view_.value(u, v); }
  Sample sample(uint32_t u, uint32_t v, float threshold, unsigned) const override {
    const float x = view_.value(u, v);
    return {x, threshold <= x};
  }
  void lit_sorted(std::span<const TexelQuery> queries, unsigned, uint8_t* lit) const override {
    for (size_t i = 0; i < queries.size(); ++i) lit[i] = queries[i].threshold <= view_.value(queries[i].u, queries[i].v);
  }

 private:
  RawTileView view_;
};

// MH and MMH share one format and decoder; the view points into the owned payload.
class MhDecodedTile final : public DecodedTile {
 public:
  static Result<std::shared_ptr<const DecodedTile>> make(std::span<const uint8_t> payload) {
    auto tile = std::shared_ptr<MhDecodedTile>(new MhDecodedTile(payload));
    auto view = MhTileView::parse(tile->payload_);
    if (!view) return view.error();
    tile->view_ = std::move(*view);
    return std::shared_ptr<const DecodedTile>(std::move(tile));
  }
  uint32_t size() const override { return view_.size(); }
  float value(uint32_t u, uint32_t v, unsigned max_level) const override {
    return view_.lookup(u, v, max_level == 255 ? kMhAllLevels : max_level);
  }
  // The embedded skip list is inside the payload; the view's own copy (or derived list) is not.
  size_t memory_bytes() const override { return payload_.size() + sizeof(*this) + view_.derived_bytes(); }
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const override {
    return view_.pcf_lit_count(u0, v0, kw, kh, threshold, 0.0f);
  }
  void lit_sorted(std::span<const TexelQuery> queries, unsigned max_level, uint8_t* lit) const override {
    view_.lit_sorted(queries, max_level == 255 ? kMhAllLevels : max_level, lit);
  }
  void lit_count_sorted(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const override {
    view_.pcf_count_sorted(corners, k, counts);
  }
  // SBE16a-style parts: header (root value included), embedded skip list, one record (mask +
  // block offset) per stored node with children, one float per stored valued node but the root.
  std::vector<SizePart> size_breakdown() const override {
    const MhStats& st = view_.stats();
    const bool root_has_children = st.stream_bytes > 0;  // a leaf root has no node stream
    const uint64_t record = 1 + st.offset_width;
    const uint64_t inner_records = st.inner_nodes - (root_has_children ? 1 : 0);  // the root's is the header's
    const uint64_t inner_values = inner_records;
    const uint64_t leaf_values = st.leaf_nodes - (root_has_children ? 0 : 1);
    std::vector<SizePart> parts{{"header", st.header_bytes},
                                {"skip list", st.skip_list_bytes},
                                {"inner node records", inner_records * record},
                                {"empty node records", st.empty_nodes * record},
                                {"inner node values", inner_values * 4},
                                {"leaf values", leaf_values * 4}};
    uint64_t counted = 0;
    for (const SizePart& p : parts) counted += p.bytes;
    // Nothing else is in the format; a remainder would mean these counts drifted from it.
    if (counted != st.payload_bytes) parts.push_back({"unaccounted", st.payload_bytes - counted});
    return parts;
  }
  std::vector<StructureCount> structure_counts() const override {
    const MhStats& st = view_.stats();
    return {{"nodes", "inner", st.inner_nodes},
            {"nodes", "empty", st.empty_nodes},
            {"nodes", "leaf", st.leaf_nodes},
            {"nodes", "blocks", st.blocks},
            {"nodes", "block_references", st.block_references},
            {"nodes", "levels_in_tile", st.levels, true}};
  }
  const MhTileView& view() const { return view_; }

 private:
  explicit MhDecodedTile(std::span<const uint8_t> payload) : payload_(payload.begin(), payload.end()) {}
  std::vector<uint8_t> payload_;
  MhTileView view_;
};

// DAG-MH: topology DAG + treelets + chunked values; same lookups through its own view.
class DagMhDecodedTile final : public DecodedTile {
 public:
  static Result<std::shared_ptr<const DecodedTile>> make(std::span<const uint8_t> payload) {
    auto tile = std::shared_ptr<DagMhDecodedTile>(new DagMhDecodedTile(payload));
    auto view = DagMhTileView::parse(tile->payload_);
    if (!view) return view.error();
    tile->view_ = std::move(*view);
    return std::shared_ptr<const DecodedTile>(std::move(tile));
  }
  uint32_t size() const override { return view_.size(); }
  float value(uint32_t u, uint32_t v, unsigned max_level) const override {
    return view_.lookup(u, v, max_level == 255 ? kDagMhAllLevels : max_level);
  }
  size_t memory_bytes() const override { return payload_.size() + sizeof(*this) + view_.derived_bytes(); }
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const override {
    return view_.pcf_lit_count(u0, v0, kw, kh, threshold, 0.0f);
  }
  void lit_sorted(std::span<const TexelQuery> queries, unsigned max_level, uint8_t* lit) const override {
    view_.lit_sorted(queries, max_level == 255 ? kDagMhAllLevels : max_level, lit);
  }
  void lit_count_sorted(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const override {
    view_.pcf_count_sorted(corners, k, counts);
  }
  // SE21 Tables 3 and 4: topology (DAG nodes, treelets) against values (chunk parts).
  std::vector<SizePart> size_breakdown() const override {
    const DagMhStats& st = view_.stats();
    return {{"header", st.header_bytes},
            {"DAG node masks", st.dag_mask_bytes},
            {"DAG node refs", st.dag_ref_bytes},
            {"DAG node value counts", st.dag_count_bytes},
            {"treelets", st.treelet_bytes},
            {"chunk offsets", st.chunk_table_bytes},
            {"chunk representatives", st.representative_bytes},
            {"difference bitmaps", st.bitmap_bytes},
            {"grid constants", st.grid_bytes},
            {"multipliers", st.multiplier_bytes},
            {"raw float values", st.raw_value_bytes}};
  }
  std::vector<StructureCount> structure_counts() const override {
    const DagMhStats& st = view_.stats();
    return {{"dag", "dag_nodes", st.dag_nodes},
            {"dag", "treelets", st.treelets},
            {"dag", "values", st.values},
            {"dag", "chunks", st.chunks},
            {"dag", "representative_values", st.representative_values},
            {"dag", "quantized_values", st.quantized_values},
            {"dag", "raw_values", st.raw_values}};
  }

 private:
  explicit DagMhDecodedTile(std::span<const uint8_t> payload) : payload_(payload.begin(), payload.end()) {}
  std::vector<uint8_t> payload_;
  DagMhTileView view_;
};

}  // namespace

uint32_t DecodedTile::lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const {
  uint32_t lit = 0;
  for (uint32_t v = v0; v < v0 + kh; ++v)
    for (uint32_t u = u0; u < u0 + kw; ++u) lit += this->lit(u, v, threshold);
  return lit;
}

Result<std::shared_ptr<const DecodedTile>> decode_raw_tile(std::span<const uint8_t> payload) {
  auto view = RawTileView::parse(payload);
  if (!view) return view.error();
  return std::shared_ptr<const DecodedTile>(std::make_shared<RawDecodedTile>(std::move(*view)));
}

Result<std::shared_ptr<const DecodedTile>> decode_mh_tile(std::span<const uint8_t> payload) {
  return MhDecodedTile::make(payload);
}

Result<std::shared_ptr<const DecodedTile>> decode_dagmh_tile(std::span<const uint8_t> payload) {
  return DagMhDecodedTile::make(payload);
}

Result<std::shared_ptr<const DecodedTile>> decode_tile(store::Method method, std::span<const uint8_t> payload) {
  if (TileDecoder decoder = find_decoder(method)) return decoder(payload);
  std::string name = store::method_from_byte(uint8_t(method)) ? store::method_name(method)
                                                              : "byte " + std::to_string(uint8_t(method));
  return make_error(ErrorCode::unsupported, "no decoder for method '" + name + "'");
}

}  // namespace shadowtiles
