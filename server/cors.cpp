#include "server/cors.hpp"

#include <algorithm>

#include "server/http_response.hpp"

namespace shadowtiles::server {
namespace {
constexpr const char* kAllowedMethods = "GET, HEAD, POST, OPTIONS";
}

bool CorsPolicy::allows(std::string_view origin) const {
  return std::find(origins_.begin(), origins_.end(), origin) != origins_.end();
}

void CorsPolicy::decorate(const httplib::Request& req, httplib::Response& res) const {
  if (!enabled()) return;
  res.set_header("Vary", "Origin");
  if (!req.has_header("Origin")) return;
  std::string origin = req.get_header_value("Origin");
  if (!allows(origin)) return;
  res.set_header("Access-Control-Allow-Origin", origin);
  // Clients revalidate tiles with If-None-Match, so scripts need to read the ETag.
  res.set_header("Access-Control-Expose-Headers", "ETag, X-Shadow-Outside-Map, X-Shadow-Receivers, X-Shadowtiles-Build");
}

void CorsPolicy::answer_options(const httplib::Request& req, httplib::Response& res) const {
  res.set_header("Allow", kAllowedMethods);
  const bool preflight = req.has_header("Origin") && req.has_header("Access-Control-Request-Method");
  if (!preflight) {
    res.status = 204;
    return;
  }
  if (!enabled() || !allows(req.get_header_value("Origin"))) {
    send_error(res, 403, "origin_not_allowed", "cross-origin requests from this origin are not allowed");
    return;
  }
  res.status = 204;
  res.set_header("Access-Control-Allow-Methods", kAllowedMethods);
  res.set_header("Access-Control-Allow-Headers", "Content-Type, If-None-Match");
  res.set_header("Access-Control-Max-Age", "600");
}

}  // namespace shadowtiles::server
