#include "store/blob.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

namespace shadowtiles::store {
namespace {

std::vector<uint8_t> random_bytes(size_t size, uint64_t seed, bool compressible = false) {
  std::mt19937_64 rng(seed);
  std::vector<uint8_t> bytes(size);
  for (size_t i = 0; i < size; ++i) {
    bytes[i] = compressible ? static_cast<uint8_t>((i / 64) % 7 + (rng() % 16 == 0))
                            : static_cast<uint8_t>(rng());
  }
  return bytes;
}

// A realistic small blob (compressible so the zstd frame has real structure).
std::vector<uint8_t> sample_blob() { return encode_blob(Method::mh, random_bytes(3000, 5, true), 0x5a); }

void put_u16(std::vector<uint8_t>& blob, size_t offset, uint16_t value) {
  blob[offset] = static_cast<uint8_t>(value);
  blob[offset + 1] = static_cast<uint8_t>(value >> 8);
}

TEST(Blob, RoundTripRandomPayloads) {
  const size_t sizes[] = {0, 1, 2, 100, 4096, 1u << 20};
  uint64_t seed = 1;
  for (size_t size : sizes) {
    for (bool compressible : {false, true}) {
      const std::vector<uint8_t> raw = random_bytes(size, seed++, compressible);
      const std::vector<uint8_t> blob = encode_blob(Method::dagmh, raw, 3);
      ASSERT_GE(blob.size(), kBlobHeaderSize);
      Result<BlobHeader> checked = check_blob(blob);
      ASSERT_TRUE(checked.ok()) << size << ": " << checked.error().message;
      EXPECT_EQ(checked->format_version, kBlobFormatVersion);
      EXPECT_EQ(checked->method, Method::dagmh);
      EXPECT_EQ(checked->flags, 3);
      EXPECT_EQ(checked->raw_size, size);
      EXPECT_EQ(checked->payload_size, blob.size() - kBlobHeaderSize);

      BlobHeader header{};
      Result<std::vector<uint8_t>> decoded = decode_blob(blob, &header);
      ASSERT_TRUE(decoded.ok()) << size << ": " << decoded.error().message;
      EXPECT_EQ(*decoded, raw);
      EXPECT_EQ(header.checksum, checked->checksum);
    }
  }
}

TEST(Blob, CopyAsAnotherMethodKeepsThePayloadAndRedoesTheChecksum) {
  const std::vector<uint8_t> raw = random_bytes(5000, 11, true);
  const std::vector<uint8_t> blob = encode_blob(Method::mh, raw, 0, 3);
  Result<std::vector<uint8_t>> copy = copy_blob_as(Method::mmh, blob);
  ASSERT_TRUE(copy.ok()) << copy.error().message;
  BlobHeader original{}, copied{};
  ASSERT_TRUE(decode_blob(blob, &original).ok());
  Result<std::vector<uint8_t>> decoded = decode_blob(*copy, &copied);
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(*decoded, raw);
  EXPECT_EQ(copied.method, Method::mmh);
  EXPECT_NE(copied.checksum, original.checksum);  // the ETag names the method's blob
  // The same bytes encode_blob gives for that method: one frame, two headers.
  EXPECT_EQ(*copy, encode_blob(Method::mmh, raw, 0, 3));
  std::vector<uint8_t> corrupt = blob;
  corrupt.back() ^= 1;
  EXPECT_FALSE(copy_blob_as(Method::mmh, corrupt).ok());
}

TEST(Blob, HeaderLayoutIsStable) {
  // FORMAT: these bytes must not change within a format version (other readers rely on them).
  const std::vector<uint8_t> blob = encode_blob(Method::mmh, std::vector<uint8_t>(10, 42), 0x81);
  ASSERT_GE(blob.size(), kBlobHeaderSize);
  EXPECT_EQ(0, std::memcmp(blob.data(), "STB1", 4));
  EXPECT_EQ(blob[4], 1);
  EXPECT_EQ(blob[5], 0);
  EXPECT_EQ(blob[6], 3);
  EXPECT_EQ(blob[7], 0x81);
  EXPECT_EQ(blob[8], 10);
  for (size_t i = 9; i < 16; ++i) EXPECT_EQ(blob[i], 0) << i;
  EXPECT_EQ(blob[16], blob.size() - kBlobHeaderSize);
}

TEST(Blob, SameInputSameChecksumDifferentInputDifferentChecksum) {
  const auto raw = random_bytes(500, 9);
  const auto a = check_blob(encode_blob(Method::raw, raw));
  const auto b = check_blob(encode_blob(Method::raw, raw));
  const auto c = check_blob(encode_blob(Method::mh, raw));  // header differs only
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_EQ(a->checksum, b->checksum);
  EXPECT_NE(a->checksum, c->checksum);
}

TEST(Blob, EveryTruncationIsAnError) {
  const std::vector<uint8_t> blob = sample_blob();
  for (size_t length = 0; length < blob.size(); ++length) {
    // A fresh exact-size buffer so ASan catches any read past `length`.
    const std::vector<uint8_t> cut(blob.begin(), blob.begin() + static_cast<ptrdiff_t>(length));
    Result<std::vector<uint8_t>> decoded = decode_blob(cut);
    ASSERT_FALSE(decoded.ok()) << length;
    EXPECT_EQ(decoded.error().code, ErrorCode::corrupt_data) << length;
    EXPECT_FALSE(check_blob(cut).ok()) << length;
  }
}

TEST(Blob, TrailingBytesAreAnError) {
  std::vector<uint8_t> blob = sample_blob();
  blob.push_back(0);
  Result<BlobHeader> checked = check_blob(blob);
  ASSERT_FALSE(checked.ok());
  EXPECT_EQ(checked.error().code, ErrorCode::corrupt_data);
}

TEST(Blob, EveryHeaderBitFlipIsAnError) {
  const std::vector<uint8_t> blob = sample_blob();
  for (size_t bit = 0; bit < kBlobHeaderSize * 8; ++bit) {
    std::vector<uint8_t> flipped = blob;
    flipped[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    Result<std::vector<uint8_t>> decoded = decode_blob(flipped);
    ASSERT_FALSE(decoded.ok()) << "bit " << bit;
    // A flip in the version field may read as a newer version; everything else is corruption.
    const bool version_bit = bit >= 32 && bit < 48;
    if (!version_bit) {
      EXPECT_EQ(decoded.error().code, ErrorCode::corrupt_data) << "bit " << bit;
    }
    EXPECT_FALSE(check_blob(flipped).ok()) << "bit " << bit;
  }
}

TEST(Blob, PayloadBitFlipsAreErrors) {
  const std::vector<uint8_t> blob = sample_blob();
  const size_t payload_bits = (blob.size() - kBlobHeaderSize) * 8;
  std::mt19937_64 rng(3);
  for (int sample = 0; sample < 2000; ++sample) {
    // All bits of the first bytes (frame header), then random ones.
    const size_t bit = sample < 256 ? static_cast<size_t>(sample) % payload_bits : rng() % payload_bits;
    std::vector<uint8_t> flipped = blob;
    flipped[kBlobHeaderSize + bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    Result<std::vector<uint8_t>> decoded = decode_blob(flipped);
    ASSERT_FALSE(decoded.ok()) << "payload bit " << bit;
    EXPECT_EQ(decoded.error().code, ErrorCode::corrupt_data);
  }
}

// Builds a blob whose checksum is valid but whose contents lie, as a hostile or buggy writer could.
std::vector<uint8_t> reseal(std::vector<uint8_t> blob);

TEST(Blob, ConsistentButLyingBlobsAreErrorsNotCrashes) {
  const std::vector<uint8_t> good = sample_blob();
  // raw_size claims far more than the frame holds (also more than the 4 GiB cap).
  for (uint64_t claimed : {uint64_t{3001}, uint64_t{1} << 31, uint64_t{1} << 40, ~uint64_t{0}}) {
    std::vector<uint8_t> lying = good;
    for (int i = 0; i < 8; ++i) lying[8 + i] = static_cast<uint8_t>(claimed >> (8 * i));
    lying = reseal(lying);
    Result<std::vector<uint8_t>> decoded = decode_blob(lying);
    ASSERT_FALSE(decoded.ok()) << claimed;
    EXPECT_EQ(decoded.error().code, ErrorCode::corrupt_data);
  }
  // Unknown method byte with a valid checksum.
  std::vector<uint8_t> unknown_method = good;
  unknown_method[6] = 99;
  EXPECT_EQ(check_blob(reseal(unknown_method)).error().code, ErrorCode::corrupt_data);
  // Garbage payload with a valid checksum.
  std::vector<uint8_t> garbage = good;
  for (size_t i = kBlobHeaderSize; i < garbage.size(); ++i) garbage[i] = static_cast<uint8_t>(i * 31);
  garbage = reseal(garbage);
  ASSERT_TRUE(check_blob(garbage).ok());
  EXPECT_EQ(decode_blob(garbage).error().code, ErrorCode::corrupt_data);
}

TEST(Blob, WrongMagic) {
  for (const char* magic : {"STB2", "stb1", "\0\0\0\0", "PK\3\4"}) {
    std::vector<uint8_t> blob = sample_blob();
    std::memcpy(blob.data(), magic, 4);
    Result<BlobHeader> checked = check_blob(blob);
    ASSERT_FALSE(checked.ok());
    EXPECT_EQ(checked.error().code, ErrorCode::corrupt_data);
  }
}

TEST(Blob, FutureVersionIsUnsupported) {
  std::vector<uint8_t> blob = sample_blob();
  put_u16(blob, 4, kBlobFormatVersion + 1);
  Result<std::vector<uint8_t>> decoded = decode_blob(blob);
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.error().code, ErrorCode::unsupported);
  put_u16(blob, 4, 0);
  EXPECT_EQ(check_blob(blob).error().code, ErrorCode::corrupt_data);
}

TEST(Blob, ChecksumHexFormat) {
  EXPECT_EQ(checksum_hex(0), "0000000000000000");
  EXPECT_EQ(checksum_hex(0x1234abcdULL), "000000001234abcd");
  EXPECT_EQ(checksum_hex(~0ULL), "ffffffffffffffff");
  EXPECT_EQ(checksum_hex(0xfedcba9876543210ULL), "fedcba9876543210");
}

}  // namespace
}  // namespace shadowtiles::store

// Recompute the checksum with the documented algorithm (XXH64 of header[0,24) + payload), which also
// pins that definition: if the encoder hashed something else, the resealed good blob would differ.
#include <xxhash.h>

namespace shadowtiles::store {
namespace {

std::vector<uint8_t> reseal(std::vector<uint8_t> blob) {
  std::vector<uint8_t> hashed(blob.begin(), blob.begin() + 24);
  hashed.insert(hashed.end(), blob.begin() + static_cast<ptrdiff_t>(kBlobHeaderSize), blob.end());
  const uint64_t checksum = XXH64(hashed.data(), hashed.size(), 0);
  for (int i = 0; i < 8; ++i) blob[24 + static_cast<size_t>(i)] = static_cast<uint8_t>(checksum >> (8 * i));
  return blob;
}

TEST(Blob, ChecksumDefinitionMatchesDocumentation) {
  const std::vector<uint8_t> blob = sample_blob();
  EXPECT_EQ(reseal(blob), blob);
}

}  // namespace
}  // namespace shadowtiles::store
