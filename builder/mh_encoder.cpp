#include "builder/mh_encoder.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

#include "codec/mh_format.hpp"

namespace shadowtiles {
namespace F = mh_format;

namespace {

void put_u16(uint8_t* p, uint16_t x) { std::memcpy(p, &x, 2); }
void put_u32(uint8_t* p, uint32_t x) { std::memcpy(p, &x, 4); }
void put_f32(uint8_t* p, float x) { std::memcpy(p, &x, 4); }
void put_offset(uint8_t* p, uint32_t x, unsigned width) { std::memcpy(p, &x, width); }

}  // namespace

uint64_t sbe16a_reference_bytes(const MhHierarchy& h) {
  const MhNodeCounts c = count_stored_nodes(h);
  return 8 * c.inner + 4 * (c.empty + c.leaves);
}

Result<std::vector<uint8_t>> encode_mh(const MhHierarchy& h, const MhEncodeOptions& options) {
  static_assert(std::endian::native == std::endian::little, "payload written with memcpy");
  if (Status s = check_structure(h); !s) return s.error();
  const unsigned L = h.levels;

  // Block order: the reverse postorder of a depth-first walk that takes a block's children last to
  // first, i.e. the blocks in preorder for a tree (a block, then its first child's whole subtree,
  // then the next child's). Every reference points forward, as the format requires: in a DAG
  // (MMH's shared blocks) a child finishes before any of its parents. A walk's blocks below the
  // skip list then lie within the subtree's few kilobytes, where the former order (tallest subtree
  // first, i.e. level by level) put each level in its own region of the stream: one cache and TLB
  // miss per level on a deep tree.
  std::vector<uint32_t> order;
  uint64_t references = 0;
  if (h.root_mask != 0) {
    std::vector<uint8_t> seen(h.block_count(), 0);
    struct Frame {
      uint32_t block;
      unsigned children_left;  // counts down: the last child is walked first
    };
    std::vector<Frame> stack;  // as deep as the tree (check_structure bounds it by the levels)
    stack.push_back({h.root_block, F::branch_children(h.block_mask[h.root_block])});
    seen[h.root_block] = 1;
    references = 1;
    while (!stack.empty()) {
      Frame& top = stack.back();
      if (top.children_left == 0) {
        order.push_back(top.block);
        stack.pop_back();
        continue;
      }
      const uint32_t c = h.child_block[h.block_first_child[top.block] + --top.children_left];
      ++references;
      if (!seen[c]) {
        seen[c] = 1;
        stack.push_back({c, F::branch_children(h.block_mask[c])});
      }
    }
    std::reverse(order.begin(), order.end());
  }

  uint64_t records = 0, values = 0;
  for (uint32_t b : order) {
    records += F::branch_children(h.block_mask[b]);
    values += F::valued_children(h.block_mask[b]);
  }
  unsigned W = 1;
  uint64_t stream_bytes = 0;
  for (;; ++W) {
    stream_bytes = records * F::record_bytes(W) + values * 4;
    if (W == 4 || stream_bytes <= (uint64_t(1) << (8 * W))) break;
  }
  if (stream_bytes > UINT32_MAX) return make_error(ErrorCode::invalid_input, "MH encode: node stream over 4 GiB");

  std::vector<uint32_t> offset(h.block_count(), 0);
  {
    uint64_t at = 0;
    for (uint32_t b : order) offset[b] = uint32_t(at), at += F::block_bytes(h.block_mask[b], W);
  }

  const unsigned S = options.embed_skip_list ? std::min({options.skip_level, L, F::kMaxSkipLevel}) : 0;
  const uint64_t skip_bytes = S ? (uint64_t(1) << (2 * S)) * F::skip_entry_bytes(W) : 0;
  std::vector<uint8_t> out(F::kHeaderBytes + skip_bytes + stream_bytes, 0);
  uint8_t* head = out.data();
  const float root_value = mh_value_for(h.root);
  std::memcpy(head + F::kOffMagic, F::kMagic, 4);
  put_u16(head + F::kOffVersion, F::kFormatVersion);
  put_u16(head + F::kOffFlags, uint16_t((S ? F::kFlagSkipList : 0) |
                                        (references > order.size() ? F::kFlagMerged : 0)));
  put_u32(head + F::kOffSize, h.size);
  head[F::kOffLevels] = uint8_t(L);
  head[F::kOffOffsetWidth] = uint8_t(W);
  head[F::kOffSkipLevel] = uint8_t(S);
  head[F::kOffRootMask] = h.root_mask;
  put_f32(head + F::kOffRootValue, root_value);
  put_u32(head + F::kOffRootBlock, h.root_mask ? offset[h.root_block] : 0);
  put_u32(head + F::kOffStreamBytes, uint32_t(stream_bytes));
  put_u32(head + F::kOffBlockCount, uint32_t(order.size()));
  put_u32(head + F::kOffRecordCount, uint32_t(records));
  put_u32(head + F::kOffValueCount, uint32_t(values));

  uint8_t* stream = out.data() + F::kHeaderBytes + skip_bytes;
  const size_t R = F::record_bytes(W);
  for (uint32_t b : order) {
    const uint8_t mask = h.block_mask[b];
    uint8_t* p = stream + offset[b];
    for (unsigned r = 0; r < F::branch_children(mask); ++r, p += R) {
      const uint32_t c = h.child_block[h.block_first_child[b] + r];
      p[0] = h.block_mask[c];
      put_offset(p + 1, offset[c], W);
    }
    for (unsigned v = 0; v < F::valued_children(mask); ++v, p += 4)
      put_f32(p, mh_value_for(h.intervals[h.block_first_value[b] + v]));
  }

  // Skip list: walk the hierarchy down to level S for each entry.
  if (S) {
    const uint32_t side = uint32_t(1) << S;
    uint8_t* e = out.data() + F::kHeaderBytes;
    for (uint32_t y = 0; y < side; ++y) {
      for (uint32_t x = 0; x < side; ++x, e += F::skip_entry_bytes(W)) {
        float value = root_value;
        uint8_t mask = h.root_mask;
        uint32_t block = h.root_block;
        unsigned level = 0;
        for (; level < S && mask != 0; ++level) {
          const unsigned shift = S - 1 - level;
          const unsigned i = ((x >> shift) & 1u) | (((y >> shift) & 1u) << 1);
          const unsigned code = F::child_code(mask, i);
          if (code == 0) break;
          unsigned rank_r = 0, rank_v = 0;
          for (unsigned j = 0; j < i; ++j) {
            rank_r += (F::child_code(mask, j) >> 1) & 1u;
            rank_v += F::child_code(mask, j) & 1u;
          }
          if (code & 1u) value = mh_value_for(h.intervals[h.block_first_value[block] + rank_v]);
          if (code & 2u) {
            block = h.child_block[h.block_first_child[block] + rank_r];
            mask = h.block_mask[block];
          } else {
            mask = 0;
          }
        }
        if (level < S) mask = 0;
        put_f32(e, value);
        e[4] = mask;
        put_offset(e + 5, mask ? offset[block] : 0, W);
      }
    }
  }
  return out;
}

}  // namespace shadowtiles
