// Shared by the C API's translation units: the map handle, the per-thread last error and the guard
// that turns Results and exceptions into shadowtiles_status (no C++ exception crosses the C ABI).
#pragma once

#include <exception>
#include <memory>
#include <new>
#include <string>

#include "client/shadow_map.hpp"
#include "common/result.hpp"
#include "shadowtiles.h"

struct shadowtiles_map {
  std::unique_ptr<shadowtiles::ShadowMap> map;
  std::string meta_json;  // returned by shadowtiles_meta_json, lives as long as the handle
};

namespace shadowtiles::capi {

// Records the message for shadowtiles_last_error() on this thread and returns the status.
shadowtiles_status fail(shadowtiles_status status, std::string message);
shadowtiles_status fail(const Error& error);
shadowtiles_status status_of(ErrorCode code);

// Runs `body` (returning shadowtiles_status); exceptions become OUT_OF_MEMORY or INTERNAL.
template <class Body>
shadowtiles_status guarded(Body&& body) noexcept {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return fail(SHADOWTILES_OUT_OF_MEMORY, "out of memory");
  } catch (const std::exception& e) {
    return fail(SHADOWTILES_INTERNAL, std::string("internal error: ") + e.what());
  } catch (...) {
    return fail(SHADOWTILES_INTERNAL, "internal error");
  }
}

// NULL or "" -> the build's default method; else the named one (invalid_input when unknown).
Result<store::Method> method_named(const ShadowMap& map, const char* name);
// bias < 0 -> the build's default (nullopt); NaN is refused by the query itself.
inline std::optional<double> bias_of(double bias) {
  if (bias < 0) return std::nullopt;
  return bias;
}

}  // namespace shadowtiles::capi
