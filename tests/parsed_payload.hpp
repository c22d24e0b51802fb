// An encoded payload kept together with the view parsed from it (the view points into the bytes; a
// vector's buffer does not move when the struct does), for the codec tests that encode a tile and
// then read it through its format's view.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles::testing {

template <typename View>
struct ParsedPayload {
  std::vector<uint8_t> bytes;
  View view;
  bool ok = false;  // encoded and parsed; otherwise a test failure was recorded and `view` is empty
};

// Takes an encoder's result and parses it with View::parse(bytes, options...).
template <typename View, typename... ParseOptions>
ParsedPayload<View> parse_payload(Result<std::vector<uint8_t>> encoded, const ParseOptions&... options) {
  ParsedPayload<View> p;
  EXPECT_TRUE(encoded.ok()) << (encoded.ok() ? "" : encoded.error().message);
  if (!encoded.ok()) return p;
  p.bytes = std::move(*encoded);
  auto view = View::parse(p.bytes, options...);
  EXPECT_TRUE(view.ok()) << (view.ok() ? "" : view.error().message);
  if (!view.ok()) return p;
  p.view = std::move(*view);
  p.ok = true;
  return p;
}

}  // namespace shadowtiles::testing
