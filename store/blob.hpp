// The blob container (docs/architecture.md §9): how every tile and top-level payload is stored and served.
// FORMAT-defining layout, a fixed 32-byte little-endian header followed by a zstd frame:
//   offset  0  magic "STB1"            4 bytes
//   offset  4  format_version          u16   (kBlobFormatVersion)
//   offset  6  method                  u8    (store::Method)
//   offset  7  flags                   u8    (opaque to store/, owned by the encoder of `method`)
//   offset  8  raw_size                u64   (bytes after decompression)
//   offset 16  payload_size            u64   (bytes of the zstd frame that follows)
//   offset 24  checksum                u64   XXH64(seed 0) of header bytes [0,24) then the payload
// The checksum covers the header too, so any bit flip is caught; it is also the HTTP ETag
// (checksum_hex). Blobs are immutable: same bytes, same ETag.
//
// Errors: wrong magic, truncation, trailing bytes, size mismatch, checksum mismatch, unknown method,
// raw_size above kMaxBlobRawSize or zstd failure → corrupt_data; a format_version newer than this
// build → unsupported. A blob that fails is never to be served or decoded further.
// Safe on untrusted input: check_blob and decode_blob never read out of bounds, and decode_blob
// bounds its allocation by what the payload could possibly expand to before allocating.
// Thread safety: all functions may be called concurrently (zstd contexts are per thread).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles::store {

inline constexpr uint16_t kBlobFormatVersion = 1;                  // FORMAT
inline constexpr size_t kBlobHeaderSize = 32;                      // FORMAT
inline constexpr uint8_t kBlobMagic[4] = {'S', 'T', 'B', '1'};     // FORMAT
inline constexpr uint64_t kMaxBlobRawSize = uint64_t{4} << 30;     // sanity cap, 4 GiB

struct BlobHeader {
  uint16_t format_version;
  Method method;
  uint8_t flags;
  uint64_t raw_size;
  uint64_t payload_size;
  uint64_t checksum;
};

// Compresses `raw_payload` with zstd at `zstd_level` (clamped to zstd's range) and wraps it.
// Preconditions: raw_payload.size() <= kMaxBlobRawSize. Throws std::bad_alloc if zstd cannot
// allocate (its only failure on valid input).
std::vector<uint8_t> encode_blob(Method method, std::span<const uint8_t> raw_payload,
                                 uint8_t flags = 0, int zstd_level = 3);

// A copy of `blob` (as encode_blob made it) that names `method` instead, checksum redone and zstd
// frame reused: for a payload two methods of one tile share byte for byte (MMH where its merge finds
// nothing is MH's payload), without compressing it twice. Errors: those of check_blob on `blob`.
Result<std::vector<uint8_t>> copy_blob_as(Method method, std::span<const uint8_t> blob);

// Validates magic, version, method, sizes and checksum without decompressing; returns the header.
// Cheap enough for the server to run on every blob it serves.
Result<BlobHeader> check_blob(std::span<const uint8_t> blob);

// check_blob, then decompresses; the result has exactly header.raw_size bytes. On success and when
// `header` is not null, *header receives the parsed header.
Result<std::vector<uint8_t>> decode_blob(std::span<const uint8_t> blob,
                                         BlobHeader* header = nullptr);

// 16 lowercase hex digits, zero-padded: the ETag body for a blob's checksum.
std::string checksum_hex(uint64_t checksum);

}  // namespace shadowtiles::store
