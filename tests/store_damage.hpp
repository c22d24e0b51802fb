// Damages one stored tile blob in a real LMDB store (one bit flipped in the middle of the blob, which
// the blob's checksum must catch), for the tests that check a corrupt tile is an error everywhere
// (local ShadowMap, server, streaming client). The store is closed again before it returns (one LMDB
// environment per directory and process).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <vector>

#include "store/lmdb_store.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles::testing {

inline void flip_a_bit_in_stored_tile(const std::filesystem::path& store_dir, const store::TileKey& tile) {
  auto store = store::Store::open(store_dir, {store::Store::Mode::read_write});
  ASSERT_TRUE(store.ok()) << store.error().message;
  const auto key = store::encode_tile_key(tile);
  auto blob = (*store)->get(store::Database::tiles, key);
  ASSERT_TRUE(blob.ok() && blob->has_value());
  std::vector<uint8_t> bytes = **blob;
  bytes[bytes.size() / 2] ^= 0x10;
  std::vector<store::Store::Put> puts{{store::Database::tiles, {key.begin(), key.end()}, bytes}};
  ASSERT_TRUE((*store)->write(puts).ok());
}

}  // namespace shadowtiles::testing
