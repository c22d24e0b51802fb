// ShadowMap::query_batch (declared in client/shadow_map.hpp). Three parallel phases:
//   A. per chunk of points (workers claim chunks): light-space transform, Morton key of the texel,
//      biased depth, and a histogram of the keys' top bits (buckets; points off the map go to an
//      extra last bucket);
//   B. per claimed chunk: stable scatter into the buckets (one counting-sort pass over the batch);
//   C. workers claim buckets, a few at a time (the next one is fetched while this one is worked):
//      order the bucket's low key bits in a per-worker buffer that stays in cache (counting passes
//      on the top digits only, sort_low_bits), then walk its runs
//      of points per tile: the tile is looked up once per run, point queries go to the decoder's
//      shared-path walk (lit_sorted), PCF kernels inside the tile to lit_count_sorted (descents to the
//      kernels' common ancestors shared along the curve), kernels crossing a
//      tile or the map's edge and coarse levels to the per-point path. Point answers go to a byte
//      per point (BatchAnswers::lit_bytes), which the last pass turns into `lit`'s floats.
// Raw point batches take a path of their own: a raw lookup is one read of a map far larger than the
// caches, which the order above does not make cheaper, so workers claim chunks of points and answer
// each on its own (transform, a count per tile, the chunk's points grouped by tile in cache, reads),
// with no pass over the whole batch.
// Every answer is computed by the same expressions as query() / query_pcf(), so they are equal.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>
#include <type_traits>

#include "client/batch_point_blocks.hpp"
#include "client/batch_texel_keys.hpp"
#include "client/shadow_map.hpp"
#include "common/parallel_for.hpp"

namespace shadowtiles {
namespace {

using BatchItem = ShadowMap::BatchSortItem;
constexpr uint64_t kOffMap = BatchTexelKeys::kOffMapKey;
constexpr unsigned kBucketBits = 12;
constexpr size_t kMinPointsPerChunk = 8192;
constexpr size_t kChunksPerBatch = 16;
constexpr size_t kQueryBlock = 256;  // point queries handed to a decoder at once
// Buckets a worker claims at once: it knows its next bucket, and fetches it ahead (the scatter
// left the buckets in memory, not in this core's cache).
constexpr size_t kBucketGroup = 4;
// The raw path: points a chunk (its items and their copy by tile, 512 KiB, stay in a core's cache),
// and the largest map it takes (a count per tile per chunk).
constexpr size_t kChunkedPoints = 16384;
constexpr size_t kMaxChunkedTilesPerSide = 64;

// Orders items[0, n) by the key's low `bits` bits (the bits above are equal), `scratch` of n items:
// counting passes on 8-bit digits sort just the top digits, enough that about kSmallGroup items
// share a value of the sorted bits, and at least every bit from `keep_below` up (the tile's bits,
// so each tile's points stay one run). The bits below stay unordered: the decoders resume from the
// deepest node two neighbours share, computed from their coordinates, so the order inside a small
// group changes no answer and little sharing, while finishing it (an insertion sort, or a second
// pass) cost half of the batch's sort time (fzk_haus 16384², 1M points: ~500 per bucket).
constexpr size_t kSmallGroup = 4;
// Returns where the ordered items are: `items` or `scratch` (no copy back after an odd number of passes).
const BatchItem* sort_low_bits(BatchItem* items, BatchItem* scratch, size_t n, unsigned bits, unsigned keep_below) {
  if (n < 2 || bits == 0) return items;
  unsigned sorted_bits = 0;  // a multiple of 8 (or all the bits)
  while (sorted_bits < bits && ((n >> sorted_bits) > kSmallGroup || bits - sorted_bits > keep_below))
    sorted_bits += 8;
  sorted_bits = std::min(sorted_bits, bits);
  BatchItem* from = items;
  BatchItem* to = scratch;
  for (unsigned shift = bits - sorted_bits; shift < bits; shift += 8) {  // least significant first
    const unsigned digit_bits = std::min(8u, bits - shift);
    const uint64_t digit_mask = (uint64_t(1) << digit_bits) - 1;
    uint32_t count[257] = {};
    for (size_t i = 0; i < n; ++i) ++count[((from[i].key >> shift) & digit_mask) + 1];
    for (unsigned d = 0; d < digit_mask; ++d) count[d + 1] += count[d];
    for (size_t i = 0; i < n; ++i) to[count[(from[i].key >> shift) & digit_mask]++] = from[i];
    std::swap(from, to);
  }
  return from;
}

}  // namespace

Status ShadowMap::query_batch(std::span<const Vec3> points, store::Method method, const BatchOptions& options,
                              BatchAnswers& out) const {
  // After an error the answers are empty, not the last batch's or a part of this one's.
  out.lit.clear();
  out.outside.clear();
  const unsigned kernel = options.kernel;
  if (kernel == 0 || kernel % 2 == 0 || kernel > kMaxPcfKernel)
    return make_error(ErrorCode::invalid_input,
                      "pcf kernel must be odd and in [1, " + std::to_string(kMaxPcfKernel) + "]");
  if (Status s = check_method(method); !s) return s;
  const double bias_world = options.bias.value_or(meta_.default_bias);
  if (!std::isfinite(bias_world) || bias_world < 0)
    return make_error(ErrorCode::invalid_input, "bias must be finite and >= 0");
  if (Status s = check_bias(method, bias_world); !s) return s;
  const double bias_depth = frame_.depth_from_world(bias_world);
  auto max_level_or = tile_max_level(options.level);
  if (!max_level_or) return max_level_or.error();
  const unsigned max_level = *max_level_or;
  const std::optional<unsigned> level = options.level;
  // Coarse levels answered by the top tree, as query() does.
  const bool coarse = level && *level < layout_.tile_level() && top_trees_.count(method);
  // Raw: a lookup is one read of a map far larger than the caches, which the sort's order does not
  // make cheaper, so each chunk of points is answered on its own, grouped by tile in cache, with no
  // pass over the whole batch (docs/client.md, session 42). Maps of up to 64 x 64 tiles (a count
  // per tile per chunk).
  const size_t tiles_per_side = layout_.tiles_per_side();
  const bool raw_by_chunks =
      method == store::Method::raw && kernel == 1 && !coarse && tiles_per_side <= kMaxChunkedTilesPerSide;

  const size_t n = points.size();
  if (n == 0) return {};
  // Points: bytes first (lit unless the walk says otherwise), floats at the end; the raw path
  // writes the floats. PCF: floats.
  if (kernel == 1) {
    out.lit.resize(n);
    if (!raw_by_chunks) out.lit_bytes.assign(n, 1);
  } else {
    out.lit.assign(n, 1.0f);
  }
  auto parallel_for = [&](size_t count, const std::function<void(size_t, size_t)>& fn) {
    if (options.parallel_for) return options.parallel_for(count, fn);
    unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
    parallel_for_ranges(threads, count, fn);
  };
  std::mutex error_mutex;
  std::optional<Error> first_error;
  std::atomic<bool> failed{false};
  auto fail = [&](Error e) {
    std::lock_guard lock(error_mutex);
    if (!first_error) first_error = std::move(e);
    failed = true;
  };
  // The batch's error, with no answers left behind (see the top).
  auto batch_error = [&]() -> Status {
    out.lit.clear();
    out.outside.clear();
    return *first_error;
  };

  const unsigned key_bits = 2 * unsigned(std::countr_zero(layout_.resolution()));
  const unsigned bucket_bits = std::min(key_bits, kBucketBits);
  const unsigned low_bits = key_bits - bucket_bits;
  const size_t buckets = size_t(1) << bucket_bits;  // + 1: off the map
  // A few chunks per worker: the histograms (chunks x buckets) and their serial prefix sum stay small.
  const size_t points_per_chunk = std::max(kMinPointsPerChunk, (n + kChunksPerBatch - 1) / kChunksPerBatch);
  const size_t chunks = (n + points_per_chunk - 1) / points_per_chunk;
  // Buffers kept in `out` between batches (see BatchAnswers); their old contents are overwritten.
  if (out.sort_items.size() < 2 * n) out.sort_items.resize_for_overwrite(2 * n);
  BatchItem* const items = out.sort_items.data();
  BatchItem* const sorted = items + n;
  std::vector<uint32_t>& histogram = out.sort_histogram;
  histogram.assign(chunks * (buckets + 1), 0);
  const double resolution = layout_.resolution();
  const BatchTexelKeys keys = BatchTexelKeys::for_key_bits(key_bits);
  // By value: a copy in a pass is then its own local state (see the transform pass).
  auto bucket_of = [keys, low_bits, buckets](uint64_t key) {
    return key == kOffMap ? buckets : size_t(keys.code(key) >> low_bits);
  };

  // Every pass's workers claim work (chunks, then buckets) instead of taking equal shares: on a
  // shared host one core can run a third slower than the other (fzk_haus 16384², 1M points, one
  // thread: 26 and 38 M points/s pinned to either core in the same minute), and equal shares wait
  // for the slower one.
  const unsigned workers = options.parallel_for ? unsigned(std::min<size_t>(buckets, 64))
                                                : (options.threads ? options.threads
                                                                   : std::max(1u, std::thread::hardware_concurrency()));
  std::atomic<size_t> next_chunk{0};
  auto claim_chunks = [&](const std::function<void(size_t, size_t)>& pass) {
    next_chunk = 0;
    parallel_for(std::min<size_t>(workers, chunks), [&](size_t, size_t) {
      for (size_t c; !failed && (c = next_chunk.fetch_add(1, std::memory_order_relaxed)) < chunks;) pass(c, c + 1);
    });
  };

  const BatchPointBlocks point_blocks(frame_, keys, resolution, bias_depth);
  auto non_finite = [] { return make_error(ErrorCode::invalid_input, "point coordinates must be finite"); };
  const uint32_t tile_mask = layout_.tile_size() - 1;
  // Point answers for items[0, count), points of one stored tile, in blocks for the decoder's
  // shared-path walk: answers[item.index] = 1 lit, 0 shadowed (bytes in the sorted path, floats in
  // raw's). `queries`, `query_index` and `lit` hold kQueryBlock each.
  auto answer_points = [&](const DecodedTile& tile, const BatchItem* items, size_t count, auto* answers,
                           TexelQuery* queries, uint32_t* query_index, uint8_t* lit) {
    using Answer = std::remove_pointer_t<decltype(answers)>;
    for (size_t i = 0; i < count;) {
      const size_t block = std::min(kQueryBlock, count - i);
      for (size_t j = 0; j < block; ++j) {
        const BatchItem& item = items[i + j];
        queries[j] = {keys.u(item.key) & tile_mask, keys.v(item.key) & tile_mask, item.threshold};
        query_index[j] = item.index;
      }
      tile.lit_sorted({queries, block}, max_level, lit);
      // Without a branch: which points are lit is as good as random here.
      for (size_t j = 0; j < block; ++j) answers[query_index[j]] = Answer(lit[j] != 0);
      i += block;
    }
  };

  // The raw path (above): per chunk, transform, group by tile, read.
  if (raw_by_chunks) {
    const size_t tile_count = tiles_per_side * tiles_per_side;
    const size_t chunk_points = std::min(n, kChunkedPoints);
    const size_t chunk_count = (n + chunk_points - 1) / chunk_points;
    std::mutex outside_mutex;
    // Each worker's two item buffers, from the ones `out` keeps between batches (see BatchAnswers).
    const size_t worker_count = std::min<size_t>(workers, chunk_count);
    if (out.sort_items.size() < 2 * worker_count * chunk_points)
      out.sort_items.resize_for_overwrite(2 * worker_count * chunk_points);
    std::atomic<size_t> next_worker{0};
    next_chunk = 0;
    parallel_for(worker_count, [&](size_t, size_t) {
      std::vector<std::shared_ptr<const DecodedTile>> tiles(tile_count);  // this worker's, by tile index
      std::vector<uint8_t> fetched(tile_count, 0);
      BatchItem* const on_map = out.sort_items.data() + 2 * chunk_points * next_worker.fetch_add(1);
      BatchItem* const by_tile = on_map + chunk_points;
      std::vector<uint32_t> tile_start(tile_count + 1), next(tile_count);
      std::vector<uint32_t> outside;
      TexelQuery queries[kQueryBlock];
      uint32_t query_index[kQueryBlock];
      uint8_t lit[kQueryBlock];
      float* const answers = out.lit.data();
      auto tile_index = [&](uint64_t key) {
        return size_t(keys.v(key) >> tile_shift_) * tiles_per_side + (keys.u(key) >> tile_shift_);
      };
      for (size_t c; !failed && (c = next_chunk.fetch_add(1, std::memory_order_relaxed)) < chunk_count;) {
        const size_t first = c * chunk_points, end = std::min(n, first + chunk_points);
        size_t count = 0;
        std::fill(tile_start.begin(), tile_start.end(), 0u);
        const bool finite = point_blocks.for_each(points, first, end, [&](size_t block_first, size_t block_count,
                                                                           const uint64_t* block_keys,
                                                                           const float* thresholds) {
          for (size_t j = 0; j < block_count; ++j) {
            const uint32_t index = uint32_t(block_first + j);
            if (block_keys[j] == kOffMap) {
              answers[index] = 1.0f;
              outside.push_back(index);
              continue;
            }
            on_map[count++] = {block_keys[j], index, thresholds[j]};
            ++tile_start[tile_index(block_keys[j]) + 1];
          }
        });
        if (!finite) return fail(non_finite());
        for (size_t t = 0; t < tile_count; ++t) next[t] = tile_start[t], tile_start[t + 1] += tile_start[t];
        for (size_t i = 0; i < count; ++i) by_tile[next[tile_index(on_map[i].key)]++] = on_map[i];
        for (size_t t = 0; t < tile_count && !failed; ++t) {
          const uint32_t s = tile_start[t], e = tile_start[t + 1];
          if (s == e) continue;
          if (!fetched[t]) {
            auto found = shared_tile(store::TileKey{method, layout_.tile_level(), uint32_t(t % tiles_per_side),
                                                    uint32_t(t / tiles_per_side)},
                                     0);
            if (!found) return fail(found.error());
            tiles[t] = std::move(*found);
            fetched[t] = 1;
          }
          if (tiles[t])
            answer_points(*tiles[t], by_tile + s, e - s, answers, queries, query_index, lit);
          else
            for (uint32_t i = s; i < e; ++i) answers[by_tile[i].index] = 1.0f;  // empty tile: lit
        }
      }
      std::lock_guard lock(outside_mutex);
      out.outside.insert(out.outside.end(), outside.begin(), outside.end());
    });
    if (first_error) return batch_error();
    std::sort(out.outside.begin(), out.outside.end());
    return {};
  }

  // A: transform, key, histogram.
  claim_chunks([&](size_t c0, size_t c1) {
    for (size_t c = c0; c < c1 && !failed; ++c) {
      uint32_t* const hist = &histogram[c * (buckets + 1)];
      // A local copy: the histogram's stores could alias a captured value, reloaded per point.
      const auto bucket = bucket_of;
      const size_t first = c * points_per_chunk, end = std::min(n, first + points_per_chunk);
      const bool finite = point_blocks.for_each(points, first, end, [&](size_t block_first, size_t count,
                                                                         const uint64_t* block_keys,
                                                                         const float* thresholds) {
        for (size_t j = 0; j < count; ++j) {
          items[block_first + j] = {block_keys[j], uint32_t(block_first + j), thresholds[j]};
          ++hist[bucket(block_keys[j])];
        }
      });
      if (!finite) return fail(non_finite());
    }
  });
  if (first_error) return batch_error();
  // Offsets: bucket-major, chunk-minor, so the scatter is stable. Computed chunk by chunk, along
  // the histogram's rows in memory (bucket by bucket strode 16 kB per step).
  std::vector<uint32_t> bucket_start(buckets + 2, 0);
  for (size_t c = 0; c < chunks; ++c) {
    const uint32_t* hist = &histogram[c * (buckets + 1)];
    for (size_t b = 0; b <= buckets; ++b) bucket_start[b + 1] += hist[b];
  }
  for (size_t b = 0; b <= buckets; ++b) bucket_start[b + 1] += bucket_start[b];
  {
    std::vector<uint32_t> next(bucket_start.begin(), bucket_start.end() - 1);
    for (size_t c = 0; c < chunks; ++c) {
      uint32_t* hist = &histogram[c * (buckets + 1)];
      for (size_t b = 0; b <= buckets; ++b) {
        const uint32_t count = hist[b];
        hist[b] = next[b];
        next[b] += count;
      }
    }
  }
  // B: scatter.
  claim_chunks([&](size_t c0, size_t c1) {
    for (size_t c = c0; c < c1; ++c) {
      uint32_t* offset = &histogram[c * (buckets + 1)];
      for (size_t i = c * points_per_chunk, end = std::min(n, i + points_per_chunk); i < end; ++i)
        sorted[offset[bucket_of(items[i].key)]++] = items[i];
    }
  });
  for (uint32_t i = bucket_start[buckets]; i < bucket_start[buckets + 1]; ++i) out.outside.push_back(sorted[i].index);
  std::sort(out.outside.begin(), out.outside.end());

  // C: buckets claimed by workers; sorted in cache, then walked per tile run.
  const unsigned tile_key_shift = 2 * tile_shift_;
  const double k2 = double(kernel) * kernel;
  std::atomic<size_t> next_bucket{0};
  parallel_for(workers, [&](size_t, size_t) {
    std::shared_ptr<const DecodedTile> tile;  // this worker's current tile (one lookup per run)
    uint64_t tile_id = kOffMap;
    TexelQuery queries[kQueryBlock];
    uint32_t query_index[kQueryBlock];
    uint8_t lit[kQueryBlock];
    uint32_t counts[kQueryBlock];
    std::vector<BatchItem> scratch;  // the bucket sort's other half, reused: stays in this core's cache
    for (size_t b = 0, group_end = 0; !failed; ++b) {
      if (b == group_end) {  // claim the next group of buckets
        b = next_bucket.fetch_add(kBucketGroup, std::memory_order_relaxed);
        if (b >= buckets) break;
        group_end = std::min(buckets, b + kBucketGroup);
      }
      const uint32_t s = bucket_start[b], e = bucket_start[b + 1];
      if (b + 1 < group_end)  // the group's next bucket, while this one is sorted and walked
        for (uint32_t i = e, next_end = bucket_start[b + 2]; i < next_end; i += 64 / sizeof(BatchItem))
          __builtin_prefetch(&sorted[i]);
      if (s == e) continue;
      // Always ordered, even sparse buckets whose points share no node below the skip-list entry:
      // skipping the sort saved 10-15% of MH/DAG-MH instructions but cost 6-10% of their time.
      // `bucket` indexes like `sorted` (from s), into whichever array the sort left the order in.
      if (scratch.size() < e - s) scratch.resize(e - s);
      const BatchItem* const ordered = sort_low_bits(&sorted[s], scratch.data(), e - s, low_bits, tile_key_shift);
      auto bucket = [ordered, s](uint32_t i) -> const BatchItem& { return ordered[i - s]; };
      for (uint32_t run = s; run < e && !failed;) {
        const uint64_t id = keys.code(bucket(run).key) >> tile_key_shift;
        uint32_t run_end = run + 1;
        while (run_end < e && (keys.code(bucket(run_end).key) >> tile_key_shift) == id) ++run_end;
        const uint32_t tu = keys.u(bucket(run).key) >> tile_shift_, tv = keys.v(bucket(run).key) >> tile_shift_;
        if (id != tile_id) {
          auto found = shared_tile(store::TileKey{method, layout_.tile_level(), tu, tv}, 0);
          if (!found) return fail(found.error());
          tile = std::move(*found);
          tile_id = id;
        }
        if (kernel == 1) {
          if (coarse) {
            for (uint32_t i = run; i < run_end; ++i) {
              const BatchItem& item = bucket(i);
              auto value = top_value(method, keys.u(item.key), keys.v(item.key), *level);
              out.lit_bytes[item.index] = value ? uint8_t(item.threshold <= *value) : uint8_t(1);
            }
          } else if (tile) {
            answer_points(*tile, &bucket(run), run_end - run, out.lit_bytes.data(), queries, query_index, lit);
          }  // empty tile: lit (already 1)
        } else {
          const int64_t half = kernel / 2, size = layout_.tile_size();
          size_t block = 0;  // kernels inside the tile, handed to the decoder together (shared descents)
          auto flush = [&] {
            tile->lit_count_sorted({queries, block}, kernel, counts);
            for (size_t j = 0; j < block; ++j) out.lit[query_index[j]] = float(double(counts[j]) / k2);
            block = 0;
          };
          for (uint32_t i = run; i < run_end; ++i) {
            const BatchItem& item = bucket(i);
            const int64_t gu = keys.u(item.key), gv = keys.v(item.key);
            const int64_t lu = gu & tile_mask, lv = gv & tile_mask;
            uint64_t count;
            if (!level && tile && lu >= half && lv >= half && lu + half < size && lv + half < size) {
              queries[block] = {uint32_t(lu - half), uint32_t(lv - half), item.threshold};
              query_index[block] = item.index;
              if (++block == kQueryBlock) flush();
              continue;
            } else if (!level && !tile && lu >= half && lv >= half && lu + half < size && lv + half < size) {
              count = uint64_t(kernel) * kernel;  // inside an empty tile: all lit
            } else {
              auto samples = pcf_lit_samples(method, gu, gv, kernel, item.threshold, max_level, level);
              if (!samples) return fail(samples.error());
              count = *samples;
            }
            out.lit[item.index] = float(double(count) / k2);
          }
          if (block > 0) flush();
        }
        run = run_end;
      }
    }
  });
  if (first_error) return batch_error();
  // The point answers' bytes to floats, in the callers' order (the walk wrote them in the sort's).
  if (kernel == 1)
    claim_chunks([&](size_t c0, size_t c1) {
      const size_t first = c0 * points_per_chunk, end = std::min(n, c1 * points_per_chunk);
      const uint8_t* const bytes = out.lit_bytes.data();
      float* const answers = out.lit.data();
      for (size_t i = first; i < end; ++i) answers[i] = float(bytes[i]);
    });
  return {};
}

}  // namespace shadowtiles
