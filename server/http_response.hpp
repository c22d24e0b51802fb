// Small helpers every route uses to answer: JSON bodies, JSON errors {"error": ..., "code": ...},
// and the mapping from library errors (common/result.hpp) to HTTP statuses (docs/architecture.md §13: the server
// maps error codes to HTTP statuses). Client mistakes are 4xx; only failures of the store itself
// (a corrupt blob, an I/O error) are 5xx.
// Thread safety: stateless functions. The messages placed in responses never echo unbounded client
// input (request_parsing.cpp bounds what it quotes).
#pragma once

#include <string>
#include <string_view>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "common/result.hpp"

namespace shadowtiles::server {

struct HttpError {
  int status = 400;
  std::string code;     // machine-readable, e.g. "invalid_input", "payload_too_large"
  std::string message;  // for humans
};

// invalid_input, unsupported → 400; not_found → 404; corrupt_data, io_error, out_of_space → 500.
HttpError http_error_for(const Error& error);

void send_json(httplib::Response& res, int status, const nlohmann::json& body);
void send_error(httplib::Response& res, const HttpError& error);
void send_error(httplib::Response& res, int status, std::string_view code, std::string_view message);

// Every answer computed from or read out of a build names it (the build id = meta config_hash), so
// a client can tell which build answered across a swap (docs: config/README.md "Swapping builds").
inline constexpr const char* kBuildHeader = "X-Shadowtiles-Build";
inline void set_build_header(httplib::Response& res, const std::string& build_id) { res.set_header(kBuildHeader, build_id); }

// The media type of a Content-Type header, lowercased, without parameters ("; charset=...").
std::string media_type(std::string_view content_type);

}  // namespace shadowtiles::server
