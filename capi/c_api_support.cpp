#include "capi/c_api_support.hpp"

#include <utility>

namespace shadowtiles::capi {
namespace {
thread_local std::string last_error;
}

shadowtiles_status fail(shadowtiles_status status, std::string message) {
  last_error = std::move(message);
  return status;
}

shadowtiles_status status_of(ErrorCode code) {
  switch (code) {
    case ErrorCode::invalid_input: return SHADOWTILES_INVALID_INPUT;
    case ErrorCode::corrupt_data: return SHADOWTILES_CORRUPT_DATA;
    case ErrorCode::not_found: return SHADOWTILES_NOT_FOUND;
    case ErrorCode::io_error: return SHADOWTILES_IO_ERROR;
    case ErrorCode::out_of_space: return SHADOWTILES_OUT_OF_SPACE;
    case ErrorCode::unsupported: return SHADOWTILES_UNSUPPORTED;
  }
  return SHADOWTILES_INTERNAL;
}

shadowtiles_status fail(const Error& error) { return fail(status_of(error.code), error.message); }

Result<store::Method> method_named(const ShadowMap& map, const char* name) {
  if (name == nullptr || *name == '\0') return map.default_method();
  return store::parse_method(name);
}

}  // namespace shadowtiles::capi

extern "C" const char* shadowtiles_last_error(void) { return shadowtiles::capi::last_error.c_str(); }
