#include "bench/harness/stability_report.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

namespace shadowtiles::bench {
namespace {

std::string percent(double rate) { return fmt::format("{:.3f}%", 100.0 * rate); }

std::string bytes_text(uint64_t bytes) {
  if (bytes >= (10u << 20)) return fmt::format("{:.1f} MiB", double(bytes) / (1 << 20));
  if (bytes >= (10u << 10)) return fmt::format("{:.1f} KiB", double(bytes) / (1 << 10));
  return fmt::format("{} B", bytes);
}

std::string escape_cell(std::string text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += "\\|";
    else if (c == '\n') out += ' ';
    else out += c;
  }
  return out;
}

void table(std::string& md, const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  md += "|";
  // append, not operator+ chains: GCC 12 reports a false -Wrestrict on the latter.
  for (const auto& h : header) md.append(" ").append(escape_cell(h)).append(" |");
  md += "\n|";
  for (size_t i = 0; i < header.size(); ++i) md += "---|";
  md += "\n";
  for (const auto& row : rows) {
    md += "|";
    for (const auto& cell : row) md.append(" ").append(escape_cell(cell)).append(" |");
    md += "\n";
  }
  md += "\n";
}

// What the suite found and what was done about it (figures from the runs named in each item).
const char* kFindings = R"(## Findings and fixes

1. **Fixed by exit caps (on by default since issue #14; `--no-exit-caps` turns them off): lossless
   methods leaked light that raw does not, at silhouettes and ridges** (`builder/receiver_surface_caps.cpp`;
   this suite builds with it; cost where they were off by default: ×1.45–2.2 bytes on compressible scenes (nefertiti, terragen 4096²: ×1.51, ×1.45; fzk_haus
   8192²: ×1.0). The cap pass costs little since builder 0.3.0: rows of the triangle's span, closed form
   inside it, exact clipping only on edges, bit-identical to per-texel clipping (tests/
   test_receiver_surface_caps*); fzk_haus 8192² builds in 14–17 s with caps vs 13.5–14.7 s without,
   was 253 s). The dual-depth interval is computed on the
   texel *centre's* ray, but receivers lie anywhere in the texel. Just inside a silhouette (the back of the
   bust) or behind a ridge at a low sun, a surface facing away from the light sits, within the texel, at a
   depth between the centre ray's entry and exit: it is in shadow, raw (the lower bound) says so, but a value
   picked inside the interval lights it. Before the fix (quick mode, 512², 5,000 receivers): nefertiti MH
   false lit 100 vs raw's 85; terragen sun 10° 273 vs 237, sun 60° 105 vs 77; oahu sun 2° 738 vs 459. The
   bench's open finding (terragen 1024², MH 122 false lit vs raw 96; 2048² 75 vs 55) is this. Fix: each
   exit is capped (minus the exit margin) by the shallowest depth, inside the texel's square, of every
   surface a shadowed receiver can lie on: back faces of closed meshes and heightfields, and open triangles,
   each clipped exactly to the square. After: every lossless method's false-lit count equals raw's in every
   row below, and no lossless answer is worse than raw's ("0 worse"). Cost in MH bytes (same builds):
   nefertiti 2048² (sun 135/45) 52,853 → 84,528 B (×1.6); terragen 1024² (sun 135/30) 46,477 → 102,026 B
   (×2.2). It is conservative where solids intersect (a back face inside another closed mesh also caps).
   Regression tests: `tests/test_stability.cpp` (ClosedBustLeaksNoMoreThanRaw, TerrainLeaksNoMoreThanRawAtLowSun).
2. **Fixed: a point beyond the far plane at a miss texel was answered shadowed** (scenario 7, "below a
   flat scene"). Misses store value 1 (the far plane) and the query compared the point's depth with it,
   so a point deeper than 1 was shadowed although nothing lies above it (a flat scene's depth range was
   its 1e-5 padding, so a point 1 unit under it had depth ~1e5). Clamping the query depth to 1 alone is
   wrong while geometry can lie on the far plane. Fix (builder 0.3.0): `LightFrame::fit` adds a far
   margin behind the deepest geometry (16 texels, or 4 exit margins if more, plus two CPVS depth
   steps), so no surface reaches depth 1; queries clamp the receiver's depth to 1 before the bias
   (`ShadowMap::biased_depth`, every method, point and PCF); a heightfield's far-plane exit is pulled
   back by the exit margin like any exit, so receivers beyond the far plane stay shadowed under terrain.
   Regression tests: `tests/test_far_plane.cpp`.
3. **Fixed, tiling:** stored depths differed by float rounding between tilings (each tile's BVH is in
   tile-local float coordinates; max 8.6e-7 of the depth range on nefertiti), which flipped one raw PCF
   sample (terragen 2048², one tile vs 128² tiles). Fix (builder 0.3.0): each hit's depth is
   re-evaluated in double from the hit triangle's global light-space plane; with exit caps the exit's
   slope term (which belongs to whichever of two edge-sharing triangles the ray hit) is left to the cap,
   which bounds it exactly. Raw's stored values are now bit-identical between tilings (scenario 4), and
   so are the renderer's intervals (`StabilityTileSeams.RenderedIntervalsAreBitIdenticalUnderAnyTiling`,
   terragen and nefertiti 1024², one tile vs 128² tiles). Interval methods may still answer points inside
   an interval differently per tiling, within their contract.
4. **Fixed: CPVS answers differed between tilings where raw is lit** (terragen 2048²: 6 points). The depth
   step holding a texel's entry was free and resolved per tile (merging and leaf reuse depend on the
   tile). Now it must be lit (`cpvs::step_bounds`): every receiver raw lights falls in a step at or before
   the entry's, so CPVS lights it too, under any tiling; the price is light for receivers less than one
   step behind the entry. CPVS still leaks most at grazing sun (scenario 3).
5. **The far-plane exit rule** (MMH authors' code) lights the floor under a one-sided roof: scenario 1
   measures it; our rule (open mesh: exit = entry) keeps every lossless answer equal to raw's there.
6. **Fixed: under `--receivers surfaces`, a receiver less than the bias under its occluder on a slope
   leaked** (scenario 9, bunny 2048²: MH/MMH/DAG-MH 115 false lit vs raw 114 of 20,000). The coplanar
   rule dropped it from the second layer, while raw, comparing with the texel centre's depth, shadowed
   it. Fix (builder 0.3.2, docs/receiver-contracts.md "near cover"): a point covered by another surface
   by less than the coplanar epsilon is in the second layer where it lies deeper than the texel's first
   hit plus the bias, in the build's caps and in verify's reference. After: 114 vs 114, 0 worse; DAG-MH
   40,441 → 41,889 B there. Regression test: `tests/test_second_layer_caps.cpp`.

)";

const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#7f7f7f"};

}  // namespace

std::vector<std::string> elevation_subjects(const std::vector<StabilityRow>& rows) {
  std::vector<std::string> subjects;
  for (const StabilityRow& r : rows)
    if (!std::isnan(r.elevation) && std::find(subjects.begin(), subjects.end(), r.subject) == subjects.end())
      subjects.push_back(r.subject);
  return subjects;
}

std::string error_vs_elevation_svg(const std::vector<StabilityRow>& rows, const std::string& subject) {
  std::map<std::string, std::vector<const StabilityRow*>> by_method;
  std::vector<std::string> methods;
  std::set<double> elevations;
  double max_rate = 0;
  for (const StabilityRow& r : rows) {
    if (r.subject != subject || std::isnan(r.elevation)) continue;
    if (!by_method.count(r.method)) methods.push_back(r.method);
    by_method[r.method].push_back(&r);
    elevations.insert(r.elevation);
    max_rate = std::max(max_rate, 100.0 * r.error_rate());
  }
  if (methods.empty()) return {};
  const double width = 640, height = 400, left = 70, right = 150, top = 40, bottom = 50;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  // y axis: a round top above the largest error.
  double y_max = 0.01;
  for (double step : {0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0})
    if (max_rate <= step) { y_max = step; break; } else y_max = step;
  // x axis: log of the elevation, so 2, 5 and 10 degrees are apart.
  const double x_lo = std::log(*elevations.begin()), x_hi = std::log(*elevations.rbegin());
  auto x_of = [&](double e) { return left + (x_hi > x_lo ? (std::log(e) - x_lo) / (x_hi - x_lo) : 0.5) * plot_w; };
  auto y_of = [&](double rate) { return top + plot_h - std::min(rate / y_max, 1.0) * plot_h; };
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      "<text x=\"{2}\" y=\"22\" font-size=\"15\">{3}: wrong answers vs sun elevation (solid: all, dashed: false lit)</text>\n",
      width, height, left, subject);
  for (int i = 0; i <= 5; ++i) {
    const double rate = y_max * i / 5, y = y_of(rate);
    svg += fmt::format("<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n", left, y,
                       left + plot_w, y);
    svg += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">{:g}%</text>\n", left - 6, y + 4, rate);
  }
  for (double e : elevations)
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{:g}°</text>\n", x_of(e),
                       top + plot_h + 18, e);
  svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">sun elevation (log scale)</text>\n",
                     left + plot_w / 2, height - 8);
  svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\"/>\n", left, top,
                     plot_w, plot_h);
  for (size_t m = 0; m < methods.size(); ++m) {
    auto points = by_method[methods[m]];
    std::sort(points.begin(), points.end(), [](auto* a, auto* b) { return a->elevation < b->elevation; });
    const char* colour = kColours[m % std::size(kColours)];
    std::string all, lit;
    for (const StabilityRow* r : points) {
      all += fmt::format("{:.1f},{:.1f} ", x_of(r->elevation), y_of(100.0 * r->error_rate()));
      lit += fmt::format("{:.1f},{:.1f} ", x_of(r->elevation), y_of(100.0 * r->false_lit_rate()));
    }
    svg += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"/>\n", all, colour);
    svg += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" "
                       "stroke-dasharray=\"5,4\"/>\n", lit, colour);
    for (const StabilityRow* r : points)
      svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3\" fill=\"{}\"/>\n", x_of(r->elevation),
                         y_of(100.0 * r->error_rate()), colour);
    const double ly = top + 10 + 18 * double(m);
    svg += fmt::format("<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"2\"/>\n",
                       left + plot_w + 12, ly, left + plot_w + 34, ly, colour);
    svg += fmt::format("<text x=\"{}\" y=\"{:.1f}\">{}</text>\n", left + plot_w + 40, ly + 4, methods[m]);
  }
  svg += "</svg>\n";
  return svg;
}

std::string stability_markdown(const std::vector<ScenarioResult>& results, const StabilityReportInfo& info) {
  std::string md = "# Stability: where compressed shadow methods fail\n\n";
  md += "Generated by `" + info.command + "` (issue #8; scenarios in `bench/harness/stability_*.cpp`, the same "
        "assertions as GoogleTests in `tests/test_stability*.cpp`). Do not edit by hand.\n\n";
  md += fmt::format("Machine: {}. Run time {:.0f} s{}.\n\n", info.machine, info.seconds,
                    info.quick ? " (quick mode: smaller resolutions, fewer cases)" : "");
  md += "**Reading the tables.** Every receiver is a point on the scene's surface; ground truth is an Embree "
        "occlusion ray toward the sun. *false lit* = the store says lit where the point is in shadow (a light "
        "leak); *false shadowed* = the reverse (acne, lost detail). *differs from raw* counts answers unlike "
        "raw's (the float32 lower-bound map of the same build): for the lossless methods (mh, mmh, dagmh) an "
        "answer can differ from raw only where the receiver's depth lies inside its texel's dual-depth "
        "interval. *bytes* are blobs at rest (zstd, tiles + top tree); *build s* is the shared dual-depth "
        "render (BVH + rays, summed over threads) plus the method's own encode time.\n\n";
  size_t failed = 0, total = 0;
  for (const ScenarioResult& r : results)
    for (const StabilityCheck& c : r.checks) total++, failed += !c.passed;
  md += "## Summary\n\n";
  std::vector<std::vector<std::string>> summary;
  for (const ScenarioResult& r : results) {
    size_t f = 0;
    for (const StabilityCheck& c : r.checks) f += !c.passed;
    summary.push_back({r.title, std::to_string(r.checks.size()), f ? fmt::format("**{} failed**", f) : "all pass",
                       fmt::format("{:.0f}", r.seconds)});
  }
  table(md, {"scenario", "checks", "result", "seconds"}, summary);
  md += fmt::format("{} of {} checks pass.\n\n", total - failed, total);

  md += kFindings;
  for (const ScenarioResult& r : results) {
    md += "## " + r.title + "\n\n";
    if (!r.setup.empty()) md += "Setup: " + r.setup + ".\n\n";
    if (!r.rows.empty()) {
      std::vector<std::vector<std::string>> rows;
      const bool has_elevation = !elevation_subjects(r.rows).empty();
      for (const StabilityRow& row : r.rows) {
        std::vector<std::string> cells{row.subject, std::to_string(row.resolution)};
        if (has_elevation) cells.push_back(std::isnan(row.elevation) ? "" : fmt::format("{:g}°", row.elevation));
        for (std::string c : {row.method, std::to_string(row.receivers),
                              fmt::format("{} ({})", row.false_lit, percent(row.false_lit_rate())),
                              fmt::format("{} ({})", row.false_shadowed, percent(row.false_shadowed_rate())),
                              row.method == "raw" ? "" : fmt::format("{} ({} worse)", row.differs_from_raw, row.worse_than_raw),
                              bytes_text(row.bytes), fmt::format("{:.2f}", row.build_seconds), row.note})
          cells.push_back(c);
        rows.push_back(cells);
      }
      std::vector<std::string> header{"subject", "resolution"};
      if (has_elevation) header.push_back("sun elevation");
      for (const char* h : {"method", "receivers", "false lit", "false shadowed", "differs from raw", "bytes",
                            "build s", "note"})
        header.push_back(h);
      table(md, header, rows);
      for (const std::string& subject : elevation_subjects(r.rows))
        md += fmt::format("![{0} error vs sun elevation]({1}/grazing_{0}.svg)\n\n", subject, info.chart_dir);
    }
    for (const StabilityTable& t : r.tables) {
      md += "**" + t.title + "**\n\n";
      table(md, t.header, t.rows);
    }
    std::vector<std::vector<std::string>> failing;
    for (const StabilityCheck& c : r.checks)
      if (!c.passed) failing.push_back({c.name, c.detail});
    md += fmt::format("Checks: {} of {} pass.\n\n", r.checks.size() - failing.size(), r.checks.size());
    if (!failing.empty()) {
      md += "Failed checks:\n\n";
      table(md, {"check", "detail"}, failing);
    }
    if (!r.notes.empty()) {
      md += "Notes:\n\n";
      for (const std::string& n : r.notes) md += "- " + n + "\n";
      md += "\n";
    }
  }
  return md;
}

nlohmann::ordered_json stability_json(const std::vector<ScenarioResult>& results) {
  nlohmann::ordered_json doc = nlohmann::ordered_json::array();
  for (const ScenarioResult& r : results) {
    nlohmann::ordered_json s;
    s["id"] = r.id;
    s["title"] = r.title;
    s["setup"] = r.setup;
    s["seconds"] = r.seconds;
    s["passed"] = r.passed();
    s["rows"] = nlohmann::ordered_json::array();
    for (const StabilityRow& row : r.rows)
      s["rows"].push_back({{"subject", row.subject}, {"method", row.method}, {"resolution", row.resolution},
                           {"elevation", std::isnan(row.elevation) ? nlohmann::ordered_json() : nlohmann::ordered_json(row.elevation)},
                           {"receivers", row.receivers}, {"false_lit", row.false_lit},
                           {"false_shadowed", row.false_shadowed}, {"differs_from_raw", row.differs_from_raw},
                           {"worse_than_raw", row.worse_than_raw}, {"bytes", row.bytes},
                           {"build_seconds", row.build_seconds}, {"note", row.note}});
    s["tables"] = nlohmann::ordered_json::array();
    for (const StabilityTable& t : r.tables)
      s["tables"].push_back({{"title", t.title}, {"header", t.header}, {"rows", t.rows}});
    s["checks"] = nlohmann::ordered_json::array();
    for (const StabilityCheck& c : r.checks)
      s["checks"].push_back({{"name", c.name}, {"passed", c.passed}, {"detail", c.detail}});
    s["notes"] = r.notes;
    doc.push_back(std::move(s));
  }
  return doc;
}

Result<std::vector<ScenarioResult>> stability_from_json(const nlohmann::json& doc) {
  std::vector<ScenarioResult> results;
  try {
    for (const auto& s : doc) {
      ScenarioResult r;
      r.id = s.at("id").get<std::string>();
      r.title = s.at("title").get<std::string>();
      r.setup = s.at("setup").get<std::string>();
      r.seconds = s.at("seconds").get<double>();
      for (const auto& row : s.at("rows")) {
        StabilityRow x;
        x.subject = row.at("subject").get<std::string>();
        x.method = row.at("method").get<std::string>();
        x.resolution = row.at("resolution").get<uint32_t>();
        if (row.at("elevation").is_number()) x.elevation = row.at("elevation").get<double>();
        x.receivers = row.at("receivers").get<uint64_t>();
        x.false_lit = row.at("false_lit").get<uint64_t>();
        x.false_shadowed = row.at("false_shadowed").get<uint64_t>();
        x.differs_from_raw = row.at("differs_from_raw").get<uint64_t>();
        x.worse_than_raw = row.at("worse_than_raw").get<uint64_t>();
        x.bytes = row.at("bytes").get<uint64_t>();
        x.build_seconds = row.at("build_seconds").get<double>();
        x.note = row.at("note").get<std::string>();
        r.rows.push_back(std::move(x));
      }
      for (const auto& t : s.at("tables"))
        r.tables.push_back({t.at("title").get<std::string>(), t.at("header").get<std::vector<std::string>>(),
                            t.at("rows").get<std::vector<std::vector<std::string>>>()});
      for (const auto& c : s.at("checks"))
        r.checks.push_back({c.at("name").get<std::string>(), c.at("passed").get<bool>(), c.at("detail").get<std::string>()});
      r.notes = s.at("notes").get<std::vector<std::string>>();
      results.push_back(std::move(r));
    }
  } catch (const nlohmann::json::exception& e) {
    return make_error(ErrorCode::invalid_input, std::string("not a stability results document: ") + e.what());
  }
  return results;
}

}  // namespace shadowtiles::bench
