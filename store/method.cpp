#include "store/method.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <mutex>
#include <string>

namespace shadowtiles::store {

namespace {

// The built-in methods: one line each (docs/architecture.md §14).
constexpr MethodInfo kBuiltIn[] = {
    {Method::raw, "raw", {.reference = true, .interval_exact = true}, "", "docs/architecture.md §8"},
    {Method::mh, "mh", {.hierarchical = true, .interval_exact = true, .has_top_tree = true}, "", "docs/mh.md"},
    {Method::mmh, "mmh", {.hierarchical = true, .interval_exact = true, .has_top_tree = true}, "", "docs/mh.md"},
    {Method::dagmh, "dagmh", {.hierarchical = true, .interval_exact = true, .has_top_tree = true}, "",
     "docs/dagmh.md"},
    {Method::cpvs, "cpvs", {.stores_visibility = true}, "depth quantised to the map side", "docs/cpvs.md"},
    {Method::sst, "sst", {.interval_exact = true}, "", "docs/sst.md"},
};

// Indexed by byte so a lookup is one load; `order` lists the registered bytes.
struct Registry {
  std::array<MethodInfo, 256> by_byte{};
  std::array<bool, 256> present{};
  std::vector<Method> order;
  std::mutex writers;
  Registry() {
    for (const MethodInfo& info : kBuiltIn) {
      by_byte[uint8_t(info.id)] = info;
      present[uint8_t(info.id)] = true;
      order.push_back(info.id);
    }
  }
};

Registry& registry() {
  static Registry r;
  return r;
}

std::string_view trim(std::string_view text) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return text;
}

std::string known_names() {
  std::string names;
  for (Method method : all_methods()) {
    if (!names.empty()) names += ", ";
    names += method_name(method);
  }
  return names;
}

bool valid_name(std::string_view name) {
  if (name.empty() || name.size() > 32) return false;
  return std::all_of(name.begin(), name.end(),
                     [](char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; });
}

}  // namespace

std::span<const Method> all_methods() { return registry().order; }

const MethodInfo& method_info(Method method) {
  const Registry& r = registry();
  assert(r.present[uint8_t(method)] && "method_info: method not registered");
  return r.by_byte[uint8_t(method)];
}

const char* method_name(Method method) {
  const Registry& r = registry();
  if (!r.present[uint8_t(method)]) {
    assert(false && "method_name: method not registered");
    return "unknown";
  }
  // Names are string literals (register_method's contract), so data() is NUL-terminated.
  return r.by_byte[uint8_t(method)].name.data();
}

Result<Method> parse_method(std::string_view name) {
  for (Method method : all_methods()) {
    if (name == method_info(method).name) return method;
  }
  // Clip what we echo back: the name may come from a URL.
  const std::string shown(name.substr(0, 32));
  return make_error(ErrorCode::invalid_input, "unknown method '" + shown + "' (known: " + known_names() + ")");
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
  if (registry().present[byte]) return Method(byte);
  return make_error(ErrorCode::invalid_input, "unknown method byte " + std::to_string(byte));
}

Status register_method(const MethodInfo& info) {
  Registry& r = registry();
  std::lock_guard lock(r.writers);
  const uint8_t byte = uint8_t(info.id);
  if (byte == 0) return make_error(ErrorCode::invalid_input, "register_method: byte 0 is not a method");
  if (!valid_name(info.name))
    return make_error(ErrorCode::invalid_input, "register_method: name must match [a-z0-9_]{1,32}");
  if (r.present[byte])
    return make_error(ErrorCode::invalid_input, "register_method: byte " + std::to_string(byte) + " is taken by '" +
                                                    std::string(r.by_byte[byte].name) + "'");
  for (Method m : r.order)
    if (r.by_byte[uint8_t(m)].name == info.name)
      return make_error(ErrorCode::invalid_input, "register_method: name '" + std::string(info.name) + "' is taken");
  r.by_byte[byte] = info;
  r.order.push_back(info.id);
  r.present[byte] = true;  // last, so a reader that sees it also sees the entry
  return {};
}

}  // namespace shadowtiles::store
