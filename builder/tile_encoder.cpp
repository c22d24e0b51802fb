#include "builder/tile_encoder.hpp"

#include <chrono>
#include <optional>

#include "builder/cpvs_encoder.hpp"
#include "builder/dagmh_encoder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_hierarchy.hpp"
#include "builder/mmh_merger.hpp"
#include "builder/sst_encoder.hpp"
#include "codec/raw_tile.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

}  // namespace

bool builder_supports(store::Method method) {
  switch (method) {
    case store::Method::raw:
    case store::Method::mh:
    case store::Method::mmh:
    case store::Method::dagmh:
      return true;
    case store::Method::cpvs:
      return cpvs_encoder_available();
    case store::Method::sst:
      return sst_encoder_available();
  }
  return false;
}

Result<TileEncoding> encode_tile(const std::vector<store::Method>& methods, const TileIntervals& intervals,
                                 const TileEncodeOptions& options) {
  TileEncoding encoding;
  std::optional<MhHierarchy> mh;
  // The MH is built once; its time is charged to the first method that needs it.
  auto ensure_mh = [&]() -> Status {
    if (mh) return {};
    MhBuildOptions build_options;
    build_options.construction = options.construction;
    auto built = build_mh(intervals, build_options);
    if (!built) return built.error();
    mh = std::move(*built);
    encoding.root = summarize(*mh).root;
    encoding.has_root = true;
    return {};
  };
  for (store::Method method : methods) {
    auto start = Clock::now();
    EncodedPayload out{method, {}, 0, 0};
    switch (method) {
      case store::Method::raw: {
        std::vector<float> lower(intervals.texels.size());
        for (size_t i = 0; i < lower.size(); ++i) lower[i] = intervals.texels[i].lower;
        out.payload = encode_raw_tile(intervals.size, lower);
        break;
      }
      case store::Method::mh: {
        if (Status s = ensure_mh(); !s) return s.error();
        auto bytes = encode_mh(*mh);
        if (!bytes) return bytes.error();
        out.payload = std::move(*bytes);
        out.reference_bytes = sbe16a_reference_bytes(*mh);
        break;
      }
      case store::Method::mmh: {
        if (Status s = ensure_mh(); !s) return s.error();
        auto merged = merge_mmh(*mh);
        if (!merged) return merged.error();
        auto bytes = encode_mh(*merged);
        if (!bytes) return bytes.error();
        out.payload = std::move(*bytes);
        out.reference_bytes = sbe16a_reference_bytes(*merged);
        break;
      }
      case store::Method::dagmh: {
        if (Status s = ensure_mh(); !s) return s.error();
        auto bytes = encode_dagmh(*mh);
        if (!bytes) return bytes.error();
        out.payload = std::move(*bytes);
        break;
      }
      case store::Method::cpvs: {
        auto bytes = encode_cpvs_tile(intervals, options.map_resolution);
        if (!bytes) return bytes.error();
        out.payload = std::move(*bytes);
        break;
      }
      case store::Method::sst: {
        auto bytes = encode_sst_tile(intervals);
        if (!bytes) return bytes.error();
        out.payload = std::move(*bytes);
        break;
      }
      default:
        return make_error(ErrorCode::unsupported,
                          std::string("method '") + store::method_name(method) + "' is not implemented by this builder");
    }
    out.seconds = seconds_since(start);
    encoding.payloads.push_back(std::move(out));
  }
  return encoding;
}

}  // namespace shadowtiles
