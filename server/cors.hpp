// CorsPolicy: cross-origin access from an explicit allow-list of origins (docs/architecture.md §10), off when
// the list is empty. An allowed Origin is echoed in Access-Control-Allow-Origin (never "*", so the
// list is the whole policy) and every response then carries "Vary: Origin" so shared caches keep
// per-origin copies apart. Preflight (OPTIONS with Access-Control-Request-Method) from an allowed
// origin → 204 with the allowed methods and headers; from any other origin → 403.
// Thread safety: immutable after construction. Safe on untrusted input (origins are compared
// exactly, never parsed).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <httplib.h>

namespace shadowtiles::server {

class CorsPolicy {
 public:
  explicit CorsPolicy(std::vector<std::string> origins) : origins_(std::move(origins)) {}

  bool enabled() const { return !origins_.empty(); }
  bool allows(std::string_view origin) const;

  // Adds the CORS headers to any response (success or error).
  void decorate(const httplib::Request& req, httplib::Response& res) const;
  // Answers an OPTIONS request (preflight or plain).
  void answer_options(const httplib::Request& req, httplib::Response& res) const;

 private:
  std::vector<std::string> origins_;
};

}  // namespace shadowtiles::server
