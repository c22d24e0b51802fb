#include "server/tile_renderer.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include "server/colour_maps.hpp"

namespace shadowtiles::server {
namespace {

using Kind = TileSummary::Kind;

// Light-space depth range of the scene's bounds (normalised): the value layer's colour domain.
std::pair<double, double> scene_depth_domain(const ShadowMap& map) {
  const WorldBounds& b = map.meta().scene_bounds;
  double lo = 1, hi = 0;
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 p{corner & 1 ? b.max[0] : b.min[0], corner & 2 ? b.max[1] : b.min[1], corner & 4 ? b.max[2] : b.min[2]};
    double d = map.frame().to_light(p).depth;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  lo = std::clamp(lo, 0.0, 1.0);
  hi = std::clamp(hi, lo + 1e-6, 1.0);
  return {lo, hi};
}

// One sample of a layer's data at one texel (or preview texel).
struct Sample {
  Kind kind = Kind::empty;  // stored: `value` is data; empty: a miss / empty tile
  float value = 0;
};

bool is_miss(float v) { return !(v < 1.0f); }

// Reads samples of one method, from previews or decoded tiles, remembering a few recent tiles so
// runs of pixels in one tile take no lock.
class SampleReader {
 public:
  SampleReader(const ShadowMap& map, TileSummaryCache& cache, store::Method method, bool from_previews,
               std::set<std::pair<uint32_t, uint32_t>>& corrupt)
      : map_(map), cache_(cache), method_(method), from_previews_(from_previews), corrupt_(corrupt) {}

  // Tile (tx, ty), local sample (i, j) in preview texels or tile texels. plane: 0 lower, 1 value.
  Result<Sample> at(uint32_t tx, uint32_t ty, uint32_t i, uint32_t j, int plane) {
    Slot& slot = slots_[(tx & 1) | ((ty & 1) << 1)];
    if (!slot.valid || slot.tx != tx || slot.ty != ty) {
      slot = Slot{};
      slot.tx = tx;
      slot.ty = ty;
      if (from_previews_) {
        auto summary = cache_.get(map_, method_, {tx, ty});
        if (!summary) return summary.error();
        slot.summary = *summary;
        if (slot.summary->kind == Kind::corrupt) corrupt_.insert({tx, ty});
      } else {
        auto tile = map_.tile(method_, {tx, ty});
        if (!tile && tile.error().code == ErrorCode::corrupt_data) {
          corrupt_.insert({tx, ty});
          slot.corrupt = true;
        } else if (!tile) {
          return tile.error();
        } else {
          slot.decoded = *tile;
        }
      }
      slot.valid = true;
    }
    Sample s;
    if (from_previews_) {
      s.kind = slot.summary->kind;
      if (s.kind == Kind::stored) {
        const store::TilePreview& p = *slot.summary->preview;
        const size_t k = p.index(i, j);
        s.value = plane == 0 ? p.lower[k] : p.value[k];
        if (is_miss(s.value)) s.kind = Kind::empty;
      }
    } else if (slot.corrupt) {
      s.kind = Kind::corrupt;
    } else if (slot.decoded) {
      s.value = slot.decoded->value(i, j);
      s.kind = is_miss(s.value) ? Kind::empty : Kind::stored;
    }
    return s;
  }

  // Per-tile summary (coverage, bytes).
  Result<std::shared_ptr<const TileSummary>> summary(uint32_t tx, uint32_t ty) {
    Slot& slot = slots_[(tx & 1) | ((ty & 1) << 1)];
    if (!slot.valid || slot.tx != tx || slot.ty != ty || !slot.summary) {
      slot = Slot{};
      auto got = cache_.get(map_, method_, {tx, ty});
      if (!got) return got.error();
      slot = Slot{true, tx, ty, *got, nullptr, false};
      if ((*got)->kind == Kind::corrupt) corrupt_.insert({tx, ty});
    }
    return slot.summary;
  }

 private:
  struct Slot {
    bool valid = false;
    uint32_t tx = 0, ty = 0;
    std::shared_ptr<const TileSummary> summary;
    std::shared_ptr<const DecodedTile> decoded;
    bool corrupt = false;
  };
  const ShadowMap& map_;
  TileSummaryCache& cache_;
  store::Method method_;
  bool from_previews_;
  std::set<std::pair<uint32_t, uint32_t>>& corrupt_;
  std::array<Slot, 4> slots_;
};

void put(uint8_t* px, const Rgb& c, uint8_t alpha = 255) {
  px[0] = c[0];
  px[1] = c[1];
  px[2] = c[2];
  px[3] = alpha;
}

// Colours of tiles that hold no data to draw, in the data layers.
bool put_special(uint8_t* px, Kind kind) {
  switch (kind) {
    case Kind::stored:
    case Kind::empty: return false;
    case Kind::missing: put(px, kCoverageMissing, 170); return true;
    case Kind::no_preview: put(px, kCoverageNoPreview, 120); return true;
    case Kind::corrupt: put(px, kCoverageCorrupt, 255); return true;
  }
  return false;
}

}  // namespace

Result<RenderLayer> parse_render_layer(std::string_view name) {
  for (RenderLayer l : {RenderLayer::value, RenderLayer::depth, RenderLayer::coverage, RenderLayer::bytes,
                        RenderLayer::diff})
    if (name == render_layer_name(l)) return l;
  return make_error(ErrorCode::invalid_input, "unknown layer (value, depth, coverage, bytes or diff)");
}

const char* render_layer_name(RenderLayer layer) {
  switch (layer) {
    case RenderLayer::value: return "value";
    case RenderLayer::depth: return "depth";
    case RenderLayer::coverage: return "coverage";
    case RenderLayer::bytes: return "bytes";
    case RenderLayer::diff: return "diff";
  }
  return "value";
}

unsigned max_render_zoom(uint32_t resolution) {
  const int log2r = std::bit_width(resolution) - 1;
  return unsigned(std::max(0, log2r - 8 + 3));
}

Result<RenderOutput> render_map_tile(const ShadowMap& map, TileSummaryCache& cache, const RenderRequest& request,
                                     std::chrono::steady_clock::time_point deadline) {
  const TileLayout& layout = map.layout();
  const uint64_t R = layout.resolution(), T = layout.tile_size();
  const uint64_t P = store::preview_size_for(layout.tile_size());
  const uint64_t S = uint64_t(kRenderTileSize) << request.z;  // map side in pixels at this zoom
  const uint64_t preview_side = uint64_t(layout.tiles_per_side()) * P;
  const RenderLayer layer = request.layer;
  const bool per_tile = layer == RenderLayer::coverage || layer == RenderLayer::bytes;
  const bool from_previews = per_tile || layer == RenderLayer::depth || S <= preview_side;
  const uint64_t Q = from_previews && !per_tile ? preview_side : R;  // sample grid side
  const uint64_t cell = from_previews && !per_tile ? P : T;          // samples per tile side

  RenderOutput out;
  out.image = RgbaImage(kRenderTileSize, kRenderTileSize);
  out.decoded_tiles = !from_previews;
  std::set<std::pair<uint32_t, uint32_t>> corrupt;

  // Sample coordinate under global pixel g (clamped to the map): point sampling when coarser than
  // the grid, nearest when magnifying.
  auto sample_of = [&](int64_t g) -> uint64_t {
    g = std::clamp<int64_t>(g, 0, int64_t(S) - 1);
    return S <= Q ? uint64_t(g) * (Q / S) + (Q / S) / 2 : uint64_t(g) / (S / Q);
  };
  const int64_t x0 = int64_t(request.x) * kRenderTileSize, y0 = int64_t(request.y) * kRenderTileSize;
  const int border = layer == RenderLayer::depth ? 1 : 0;  // the relief needs its neighbours
  const int side = int(kRenderTileSize) + 2 * border;
  std::vector<uint64_t> su(side), sv(side);
  for (int k = 0; k < side; ++k) {
    su[k] = sample_of(x0 + k - border);
    sv[k] = sample_of(y0 + k - border);
  }
  auto timed_out = [&] { return std::chrono::steady_clock::now() > deadline; };

  SampleReader reader(map, cache, request.method, from_previews, corrupt);
  const double depth_range = map.frame().depth_range();

  if (per_tile) {
    const uint64_t tile_pixels = S / layout.tiles_per_side();  // may be 0 (many tiles per pixel)
    for (int iy = 0; iy < side; ++iy) {
      if (timed_out()) { out.timed_out = true; return out; }
      for (int ix = 0; ix < side; ++ix) {
        const uint32_t tx = uint32_t(su[ix] / cell), ty = uint32_t(sv[iy] / cell);
        auto summary = reader.summary(tx, ty);
        if (!summary) return summary.error();
        uint8_t* px = out.image.at(ix, iy);
        const TileSummary& s = **summary;
        if (layer == RenderLayer::coverage) {
          Rgb c = s.kind == Kind::stored       ? kCoverageStored
                  : s.kind == Kind::empty      ? kCoverageEmpty
                  : s.kind == Kind::missing    ? kCoverageMissing
                  : s.kind == Kind::no_preview ? kCoverageNoPreview
                                               : kCoverageCorrupt;
          uint8_t alpha = s.kind == Kind::empty ? 150 : 230;
          // A tile grid when tiles are at least 16 pixels wide.
          if (tile_pixels >= 16 && ((x0 + ix) % int64_t(tile_pixels) == 0 || (y0 + iy) % int64_t(tile_pixels) == 0)) {
            for (auto& ch : c) ch = uint8_t(ch / 2);
            alpha = 255;
          }
          put(px, c, alpha);
        } else if (s.kind == Kind::empty) {
          // transparent
        } else if (s.kind == Kind::missing || s.kind == Kind::corrupt) {
          put_special(px, s.kind);
        } else {
          const double bits_per_texel = double(s.blob_bytes) * 8.0 / double(T * T);
          put(px, colour_at(ColourMap::inferno, (std::log2(bits_per_texel) + 6.0) / 11.0), 235);
        }
      }
    }
  } else if (layer == RenderLayer::depth) {
    std::vector<float> lower(size_t(side) * side, std::numeric_limits<float>::quiet_NaN());
    std::vector<Kind> kinds(size_t(side) * side, Kind::empty);
    for (int iy = 0; iy < side; ++iy) {
      if (timed_out()) { out.timed_out = true; return out; }
      for (int ix = 0; ix < side; ++ix) {
        auto s = reader.at(uint32_t(su[ix] / cell), uint32_t(sv[iy] / cell), uint32_t(su[ix] % cell),
                           uint32_t(sv[iy] % cell), 0);
        if (!s) return s.error();
        kinds[size_t(iy) * side + ix] = s->kind;
        if (s->kind == Kind::stored) lower[size_t(iy) * side + ix] = s->value;
      }
    }
    auto [d0, d1] = scene_depth_domain(map);
    // Height = -depth (nearer the light is higher); slopes in world units.
    const double pixel_world = map.frame().extent() / double(S);
    const double lx = -1, ly = -1, lz = 1.5, ln = std::sqrt(lx * lx + ly * ly + lz * lz);
    const double flat = lz / ln;
    for (int iy = 0; iy < int(kRenderTileSize); ++iy)
      for (int ix = 0; ix < int(kRenderTileSize); ++ix) {
        const size_t c = size_t(iy + 1) * side + (ix + 1);
        uint8_t* px = out.image.at(ix, iy);
        if (put_special(px, kinds[c])) continue;
        const float l = lower[c];
        if (std::isnan(l)) continue;
        auto at = [&](size_t k) { return std::isnan(lower[k]) ? l : lower[k]; };
        const double dhdx = -(at(c + 1) - at(c - 1)) * depth_range / (2 * pixel_world);
        const double dhdy = -(at(c + side) - at(c - side)) * depth_range / (2 * pixel_world);
        const double nn = std::sqrt(dhdx * dhdx + dhdy * dhdy + 1);
        const double shade = std::max(0.0, (-dhdx * lx - dhdy * ly + lz) / (nn * ln)) / flat;
        Rgb base = colour_at(ColourMap::relief, (l - d0) / (d1 - d0));
        const double f = std::clamp(0.3 + 0.7 * shade, 0.0, 1.15);
        put(px, {uint8_t(std::min(255.0, base[0] * f)), uint8_t(std::min(255.0, base[1] * f)),
                 uint8_t(std::min(255.0, base[2] * f))});
      }
  } else {
    auto [d0, d1] = scene_depth_domain(map);
    std::optional<SampleReader> other;
    if (layer == RenderLayer::diff) other.emplace(map, cache, *request.against, from_previews, corrupt);
    for (int iy = 0; iy < side; ++iy) {
      if (timed_out()) { out.timed_out = true; return out; }
      for (int ix = 0; ix < side; ++ix) {
        const uint32_t tx = uint32_t(su[ix] / cell), ty = uint32_t(sv[iy] / cell);
        const uint32_t i = uint32_t(su[ix] % cell), j = uint32_t(sv[iy] % cell);
        auto a = reader.at(tx, ty, i, j, 1);
        if (!a) return a.error();
        uint8_t* px = out.image.at(ix, iy);
        if (put_special(px, a->kind)) continue;
        if (layer == RenderLayer::value) {
          if (a->kind == Kind::stored) put(px, colour_at(ColourMap::viridis, (a->value - d0) / (d1 - d0)));
          continue;
        }
        auto b = other->at(tx, ty, i, j, 1);
        if (!b) return b.error();
        if (put_special(px, b->kind)) continue;
        if (a->kind == Kind::empty && b->kind == Kind::empty) continue;
        double t = 1;  // one side a miss, the other not: the largest difference
        if (a->kind == Kind::stored && b->kind == Kind::stored) {
          const double d = std::abs(double(a->value) - double(b->value));
          t = d == 0 ? 0 : (std::log10(d) + 6.0) / 6.0;
        }
        put(px, colour_at(ColourMap::inferno, t));
      }
    }
  }
  out.corrupt_tiles = unsigned(corrupt.size());
  return out;
}

nlohmann::json render_legend(const ShadowMap& map, RenderLayer layer) {
  const double range = map.frame().depth_range();
  auto [d0, d1] = scene_depth_domain(map);
  auto stops = [](ColourMap m) { return colour_stops(m); };
  nlohmann::json categories = nlohmann::json::array();
  auto category = [&](const char* label, const Rgb& c) { categories.push_back({{"label", label}, {"colour", hex_colour(c)}}); };
  nlohmann::json legend = {{"layer", render_layer_name(layer)}};
  switch (layer) {
    case RenderLayer::value:
      legend.update({{"title", "stored shadow depth"}, {"unit", "world units from the light's near plane"},
                     {"scale", "linear"}, {"min", d0 * range}, {"max", d1 * range}, {"stops", stops(ColourMap::viridis)}});
      break;
    case RenderLayer::depth:
      legend.update({{"title", "first-hit depth (relief shaded)"}, {"unit", "world units from the light's near plane"},
                     {"scale", "linear"}, {"min", d0 * range}, {"max", d1 * range}, {"stops", stops(ColourMap::relief)}});
      break;
    case RenderLayer::bytes:
      legend.update({{"title", "stored bits per texel of each tile"}, {"unit", "bits/texel"}, {"scale", "log2"},
                     {"min", 1.0 / 64}, {"max", 32.0}, {"stops", stops(ColourMap::inferno)}});
      break;
    case RenderLayer::diff:
      legend.update({{"title", "|value - value of the other method|"}, {"unit", "world units"}, {"scale", "log10"},
                     {"min", 1e-6 * range}, {"max", range}, {"stops", stops(ColourMap::inferno)}});
      break;
    case RenderLayer::coverage:
      legend.update({{"title", "tile coverage"}, {"scale", "categories"}});
      break;
  }
  category("stored", kCoverageStored);
  category("empty (no geometry)", kCoverageEmpty);
  category("missing", kCoverageMissing);
  category("no preview", kCoverageNoPreview);
  category("corrupt", kCoverageCorrupt);
  legend["categories"] = categories;
  return legend;
}

}  // namespace shadowtiles::server
