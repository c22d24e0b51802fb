#include "builder/tile_encoder.hpp"

#include <chrono>
#include <string>

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

}  // namespace

bool builder_supports(store::Method method) {
  const MethodEncoder* encoder = find_encoder(method);
  return encoder && (!encoder->available || encoder->available());
}

Result<TileEncoding> encode_tile(const std::vector<store::Method>& methods, const TileIntervals& intervals,
                                 const TileEncodeOptions& options) {
  TileEncoding encoding;
  // The MH is built once, inside the first method that needs it, which is charged its time.
  TileEncodeInput input(intervals, options);
  for (store::Method method : methods) {
    if (!builder_supports(method))
      return make_error(ErrorCode::unsupported,
                        std::string("method '") + store::method_name(method) + "' is not implemented by this builder");
    auto start = Clock::now();
    auto bytes = find_encoder(method)->encode(input);
    if (!bytes) return bytes.error();
    encoding.payloads.push_back({method, std::move(bytes->payload), seconds_since(start), bytes->reference_bytes});
  }
  if (input.mh_built()) {
    auto mh = input.mh();
    encoding.root = summarize(**mh).root;
    encoding.has_root = true;
  }
  return encoding;
}

}  // namespace shadowtiles
