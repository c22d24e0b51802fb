// The inspector page's own files (server/inspector/*), embedded in the binary at build time
// (server/embed_assets.cmake), so `shadowtiles serve` needs no install path to serve them.
// Thread safety: immutable data.
#pragma once

#include <string_view>

namespace shadowtiles::server {

struct InspectorAsset {
  std::string_view bytes;  // empty: no such file
  const char* content_type = "application/octet-stream";
};

// "index.html", "app.js", "app.css"; any other name gives an empty asset.
const InspectorAsset& inspector_asset(std::string_view name);

}  // namespace shadowtiles::server
