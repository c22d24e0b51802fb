#include "server/http_response.hpp"

#include <algorithm>
#include <cctype>

namespace shadowtiles::server {

HttpError http_error_for(const Error& error) {
  switch (error.code) {
    case ErrorCode::invalid_input:
    case ErrorCode::unsupported: return {400, error_code_name(error.code), error.message};
    case ErrorCode::not_found: return {404, "not_found", error.message};
    case ErrorCode::corrupt_data:
    case ErrorCode::io_error:
    case ErrorCode::out_of_space: break;
  }
  return {500, error_code_name(error.code), error.message};
}

void send_json(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  // `replace`: invalid UTF-8 from anywhere (a scene path in meta) must not throw mid-response.
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

void send_error(httplib::Response& res, const HttpError& error) {
  send_json(res, error.status, {{"error", error.message}, {"code", error.code}});
}

void send_error(httplib::Response& res, int status, std::string_view code, std::string_view message) {
  send_error(res, HttpError{status, std::string(code), std::string(message)});
}

std::string media_type(std::string_view content_type) {
  std::string type(content_type.substr(0, content_type.find(';')));
  auto not_space = [](unsigned char c) { return !std::isspace(c); };
  type.erase(type.begin(), std::find_if(type.begin(), type.end(), not_space));
  type.erase(std::find_if(type.rbegin(), type.rend(), not_space).base(), type.end());
  std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return type;
}

}  // namespace shadowtiles::server
