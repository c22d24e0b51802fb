#include "store/blob.hpp"

#include <zstd.h>
#define XXH_STATIC_LINKING_ONLY  // XXH64_state_t on the stack
#include <xxhash.h>

#include <algorithm>
#include <cassert>
#include <cstring>
#include <memory>
#include <new>

#include "common/byte_order.hpp"

namespace shadowtiles::store {

namespace {

// FORMAT: field offsets of the header documented in blob.hpp.
constexpr size_t kVersionOffset = 4;
constexpr size_t kMethodOffset = 6;
constexpr size_t kFlagsOffset = 7;
constexpr size_t kRawSizeOffset = 8;
constexpr size_t kPayloadSizeOffset = 16;
constexpr size_t kChecksumOffset = 24;  // the checksum covers everything before it
static_assert(kChecksumOffset + 8 == kBlobHeaderSize);

// zstd format facts used to bound decompressed size before allocating: every block has a 3-byte
// header and expands to at most 128 KiB (ZSTD_BLOCKSIZE_MAX), so a frame of n bytes yields at most
// n / 3 * 128 KiB.
constexpr uint64_t kZstdBlockHeaderSize = 3;
constexpr uint64_t kZstdBlockSizeMax = uint64_t{128} << 10;

struct CCtxDeleter {
  void operator()(ZSTD_CCtx* ctx) const { ZSTD_freeCCtx(ctx); }
};
struct DCtxDeleter {
  void operator()(ZSTD_DCtx* ctx) const { ZSTD_freeDCtx(ctx); }
};

// One context per thread: reusing it avoids re-allocating zstd's work memory for every tile.
ZSTD_CCtx* thread_cctx() {
  thread_local std::unique_ptr<ZSTD_CCtx, CCtxDeleter> ctx(ZSTD_createCCtx());
  if (!ctx) throw std::bad_alloc();
  return ctx.get();
}
ZSTD_DCtx* thread_dctx() {
  thread_local std::unique_ptr<ZSTD_DCtx, DCtxDeleter> ctx(ZSTD_createDCtx());
  if (!ctx) throw std::bad_alloc();
  return ctx.get();
}

uint64_t blob_checksum(std::span<const uint8_t> header_prefix, std::span<const uint8_t> payload) {
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  XXH64_update(&state, header_prefix.data(), header_prefix.size());
  XXH64_update(&state, payload.data(), payload.size());
  return XXH64_digest(&state);
}

Error corrupt(const std::string& what) {
  return make_error(ErrorCode::corrupt_data, "corrupt blob: " + what);
}

}  // namespace

std::vector<uint8_t> encode_blob(Method method, std::span<const uint8_t> raw_payload,
                                 uint8_t flags, int zstd_level) {
  assert(raw_payload.size() <= kMaxBlobRawSize);
  zstd_level = std::clamp(zstd_level, ZSTD_minCLevel(), ZSTD_maxCLevel());

  std::vector<uint8_t> blob(kBlobHeaderSize + ZSTD_compressBound(raw_payload.size()));
  ZSTD_CCtx* ctx = thread_cctx();
  ZSTD_CCtx_reset(ctx, ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(ctx, ZSTD_c_compressionLevel, zstd_level);
  // Content size in the frame header lets decode_blob cross-check raw_size.
  ZSTD_CCtx_setParameter(ctx, ZSTD_c_contentSizeFlag, 1);
  const size_t payload_size =
      ZSTD_compress2(ctx, blob.data() + kBlobHeaderSize, blob.size() - kBlobHeaderSize,
                     raw_payload.data(), raw_payload.size());
  // The destination is compressBound-sized, so an error can only be an allocation failure.
  if (ZSTD_isError(payload_size)) throw std::bad_alloc();
  blob.resize(kBlobHeaderSize + payload_size);

  uint8_t* h = blob.data();
  std::memcpy(h, kBlobMagic, sizeof(kBlobMagic));
  bytes::store_le<uint16_t>(h + kVersionOffset, kBlobFormatVersion);
  h[kMethodOffset] = static_cast<uint8_t>(method);
  h[kFlagsOffset] = flags;
  bytes::store_le<uint64_t>(h + kRawSizeOffset, raw_payload.size());
  bytes::store_le<uint64_t>(h + kPayloadSizeOffset, payload_size);
  const uint64_t checksum = blob_checksum(std::span(h, kChecksumOffset),
                                          std::span(blob).subspan(kBlobHeaderSize));
  bytes::store_le<uint64_t>(h + kChecksumOffset, checksum);
  return blob;
}

Result<std::vector<uint8_t>> copy_blob_as(Method method, std::span<const uint8_t> blob) {
  if (auto header = check_blob(blob); !header) return header.error();
  std::vector<uint8_t> copy(blob.begin(), blob.end());
  uint8_t* h = copy.data();
  h[kMethodOffset] = static_cast<uint8_t>(method);
  const uint64_t checksum = blob_checksum(std::span(h, kChecksumOffset),
                                          std::span(copy).subspan(kBlobHeaderSize));
  bytes::store_le<uint64_t>(h + kChecksumOffset, checksum);
  return copy;
}

Result<BlobHeader> check_blob(std::span<const uint8_t> blob) {
  if (blob.size() < kBlobHeaderSize) {
    return corrupt("truncated header (" + std::to_string(blob.size()) + " bytes)");
  }
  const uint8_t* h = blob.data();
  if (std::memcmp(h, kBlobMagic, sizeof(kBlobMagic)) != 0) return corrupt("wrong magic");

  BlobHeader header{};
  header.format_version = bytes::load_le<uint16_t>(h + kVersionOffset);
  // Version before checksum: a future version may checksum differently.
  if (header.format_version == 0) return corrupt("format version 0");
  if (header.format_version > kBlobFormatVersion) {
    return make_error(ErrorCode::unsupported,
                      "blob format version " + std::to_string(header.format_version) +
                          " is newer than this build supports (" +
                          std::to_string(kBlobFormatVersion) + ")");
  }
  header.flags = h[kFlagsOffset];
  header.raw_size = bytes::load_le<uint64_t>(h + kRawSizeOffset);
  header.payload_size = bytes::load_le<uint64_t>(h + kPayloadSizeOffset);
  header.checksum = bytes::load_le<uint64_t>(h + kChecksumOffset);

  const uint64_t available = blob.size() - kBlobHeaderSize;
  if (header.payload_size != available) {
    return corrupt("payload size " + std::to_string(header.payload_size) + " but " +
                   std::to_string(available) + " bytes follow the header");
  }
  if (header.raw_size > kMaxBlobRawSize) {
    return corrupt("raw size " + std::to_string(header.raw_size) + " above the limit");
  }
  const uint64_t actual = blob_checksum(blob.first(kChecksumOffset), blob.subspan(kBlobHeaderSize));
  if (actual != header.checksum) {
    return corrupt("checksum mismatch (stored " + checksum_hex(header.checksum) + ", computed " +
                   checksum_hex(actual) + ")");
  }
  // After the checksum: with a good checksum an unknown method means a writer bug, not a bit flip.
  Result<Method> method = method_from_byte(h[kMethodOffset]);
  if (!method) return corrupt(method.error().message);
  header.method = *method;
  return header;
}

Result<std::vector<uint8_t>> decode_blob(std::span<const uint8_t> blob, BlobHeader* header_out) {
  Result<BlobHeader> checked = check_blob(blob);
  if (!checked) return checked.error();
  const BlobHeader& header = *checked;
  const std::span<const uint8_t> payload = blob.subspan(kBlobHeaderSize);

  // Exactly one frame filling the payload, declaring raw_size: cheap header walks that reject a
  // lying raw_size before we allocate for it.
  const size_t frame_size = ZSTD_findFrameCompressedSize(payload.data(), payload.size());
  if (ZSTD_isError(frame_size) || frame_size != payload.size()) {
    return corrupt("payload is not exactly one zstd frame");
  }
  const unsigned long long content_size = ZSTD_getFrameContentSize(payload.data(), payload.size());
  if (content_size != header.raw_size) {
    return corrupt("zstd frame content size does not match raw size");
  }
  if (header.raw_size > payload.size() / kZstdBlockHeaderSize * kZstdBlockSizeMax) {
    return corrupt("raw size larger than the payload can expand to");
  }

  std::vector<uint8_t> raw(static_cast<size_t>(header.raw_size));
  const size_t written =
      ZSTD_decompressDCtx(thread_dctx(), raw.data(), raw.size(), payload.data(), payload.size());
  if (ZSTD_isError(written)) {
    return corrupt(std::string("zstd: ") + ZSTD_getErrorName(written));
  }
  if (written != raw.size()) return corrupt("decompressed size does not match raw size");
  if (header_out) *header_out = header;
  return raw;
}

std::string checksum_hex(uint64_t checksum) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex(16, '0');
  for (int i = 15; i >= 0; --i) {
    hex[static_cast<size_t>(i)] = kDigits[checksum & 0xf];
    checksum >>= 4;
  }
  return hex;
}

}  // namespace shadowtiles::store
