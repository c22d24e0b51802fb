#include "store/method.hpp"

#include <algorithm>
#include <cassert>
#include <array>
#include <string>

namespace shadowtiles::store {

namespace {

constexpr std::array<Method, 6> kAllMethods = {Method::raw,   Method::mh,   Method::mmh,
                                               Method::dagmh, Method::cpvs, Method::sst};

std::string_view trim(std::string_view text) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return text;
}

std::string known_names() {
  std::string names;
  for (Method method : kAllMethods) {
    if (!names.empty()) names += ", ";
    names += method_name(method);
  }
  return names;
}

}  // namespace

std::span<const Method> all_methods() { return kAllMethods; }

const char* method_name(Method method) {
  switch (method) {
    case Method::raw: return "raw";
    case Method::mh: return "mh";
    case Method::mmh: return "mmh";
    case Method::dagmh: return "dagmh";
    case Method::cpvs: return "cpvs";
    case Method::sst: return "sst";
  }
  assert(false && "method_name: not a Method enumerator");
  return "unknown";
}

Result<Method> parse_method(std::string_view name) {
  for (Method method : kAllMethods) {
    if (name == method_name(method)) return method;
  }
  // Clip what we echo back: the name may come from a URL.
  const std::string shown(name.substr(0, 32));
  return make_error(ErrorCode::invalid_input,
                    "unknown method '" + shown + "' (known: " + known_names() + ")");
}

Result<std::vector<Method>> parse_method_list(std::string_view names) {
  std::vector<Method> methods;
  if (trim(names).empty()) return make_error(ErrorCode::invalid_input, "empty method list");
  for (;;) {
    const size_t comma = names.find(',');
    const std::string_view item = trim(names.substr(0, comma));
    if (item.empty()) {
      return make_error(ErrorCode::invalid_input, "empty item in method list");
    }
    Result<Method> method = parse_method(item);
    if (!method) return method.error();
    if (std::find(methods.begin(), methods.end(), *method) == methods.end()) {
      methods.push_back(*method);
    }
    if (comma == std::string_view::npos) break;
    names.remove_prefix(comma + 1);
  }
  return methods;
}

Result<Method> method_from_byte(uint8_t byte) {
  for (Method method : kAllMethods) {
    if (static_cast<uint8_t>(method) == byte) return method;
  }
  return make_error(ErrorCode::invalid_input, "unknown method byte " + std::to_string(byte));
}

}  // namespace shadowtiles::store
