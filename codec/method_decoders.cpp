#include "codec/method_decoders.hpp"

#include <array>
#include <mutex>
#include <string>

#include "codec/cpvs_decoder.hpp"
#include "codec/sst_decoder.hpp"

namespace shadowtiles {
namespace {

using store::Method;

struct DecoderTable {
  std::array<TileDecoder, 256> by_byte{};
  std::mutex writers;
  DecoderTable() {
    // The built-in methods: one line each.
    by_byte[uint8_t(Method::raw)] = decode_raw_tile;
    by_byte[uint8_t(Method::mh)] = decode_mh_tile;
    by_byte[uint8_t(Method::mmh)] = decode_mh_tile;  // MMH shares MH's format
    by_byte[uint8_t(Method::dagmh)] = decode_dagmh_tile;
    by_byte[uint8_t(Method::cpvs)] = decode_cpvs_tile;
    by_byte[uint8_t(Method::sst)] = decode_sst_tile;
  }
};

DecoderTable& table() {
  static DecoderTable t;
  return t;
}

}  // namespace

TileDecoder find_decoder(store::Method method) { return table().by_byte[uint8_t(method)]; }

Status register_decoder(store::Method method, TileDecoder decoder) {
  if (!store::method_from_byte(uint8_t(method)))
    return make_error(ErrorCode::invalid_input,
                      "register_decoder: method byte " + std::to_string(uint8_t(method)) + " is not registered");
  DecoderTable& t = table();
  std::lock_guard lock(t.writers);
  if (t.by_byte[uint8_t(method)] || !decoder)
    return make_error(ErrorCode::invalid_input,
                      std::string("register_decoder: '") + store::method_name(method) + "' already has a decoder");
  t.by_byte[uint8_t(method)] = decoder;
  return {};
}

}  // namespace shadowtiles
