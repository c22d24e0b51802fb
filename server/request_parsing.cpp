#include "server/request_parsing.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>

namespace shadowtiles::server {
namespace {

Error invalid(std::string message) { return make_error(ErrorCode::invalid_input, std::move(message)); }

// Untrusted text quoted in an error message: bounded and printable, so errors stay readable.
std::string shown(std::string_view text) {
  std::string out = "'";
  for (char c : text.substr(0, 40)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  if (text.size() > 40) out += "...";
  return out + "'";
}

// The value of a parameter given at most once; nullopt when absent.
Result<std::optional<std::string>> single(const Params& params, const std::string& name) {
  auto [first, last] = params.equal_range(name);
  if (first == last) return std::optional<std::string>{};
  if (std::next(first) != last) return invalid("parameter '" + name + "' is given more than once");
  return std::optional<std::string>{first->second};
}

Status check_pcf(uint64_t pcf, unsigned max_pcf) {
  if (pcf == 0 || pcf % 2 == 0 || pcf > max_pcf)
    return invalid("pcf must be an odd kernel size in [1, " + std::to_string(max_pcf) + "]");
  return {};
}

Result<store::Method> method_named(std::string_view name) {
  auto method = store::parse_method(name);
  if (!method) return invalid("unknown method " + shown(name));
  return *method;
}

}  // namespace

Result<double> parse_finite_number(std::string_view text, std::string_view name) {
  if (text.empty()) return invalid("parameter '" + std::string(name) + "' is empty");
  double value = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec == std::errc::result_out_of_range)
    return invalid("parameter '" + std::string(name) + "' is out of range: " + shown(text));
  if (ec != std::errc() || end != text.data() + text.size())
    return invalid("parameter '" + std::string(name) + "' is not a number: " + shown(text));
  if (!std::isfinite(value)) return invalid("parameter '" + std::string(name) + "' must be finite");
  return value;
}

Result<uint64_t> parse_unsigned(std::string_view text, std::string_view name, uint64_t max) {
  if (text.empty()) return invalid("parameter '" + std::string(name) + "' is empty");
  uint64_t value = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec == std::errc() && end == text.data() + text.size() && value <= max) return value;
  if (ec == std::errc::result_out_of_range || (ec == std::errc() && end == text.data() + text.size()))
    return invalid("parameter '" + std::string(name) + "' must be at most " + std::to_string(max));
  return invalid("parameter '" + std::string(name) + "' is not an unsigned integer: " + shown(text));
}

Result<QueryOptions> options_from_params(const Params& params, unsigned max_pcf,
                                         std::span<const std::string_view> extra_allowed) {
  static constexpr std::string_view kOwn[] = {"pcf", "method", "level", "bias"};
  for (const auto& [name, value] : params) {
    if (std::find(std::begin(kOwn), std::end(kOwn), name) == std::end(kOwn) &&
        std::find(extra_allowed.begin(), extra_allowed.end(), name) == extra_allowed.end())
      return invalid("unknown parameter " + shown(name));
  }
  QueryOptions options;
  auto pcf = single(params, "pcf");
  if (!pcf) return pcf.error();
  if (*pcf) {
    auto k = parse_unsigned(**pcf, "pcf", UINT32_MAX);
    if (!k) return k.error();
    if (Status s = check_pcf(*k, max_pcf); !s) return s.error();
    options.pcf = unsigned(*k);
  }
  auto method = single(params, "method");
  if (!method) return method.error();
  if (*method) {
    auto parsed = method_named(**method);
    if (!parsed) return parsed.error();
    options.method = *parsed;
  }
  auto level = single(params, "level");
  if (!level) return level.error();
  if (*level) {
    auto parsed = parse_unsigned(**level, "level", 255);
    if (!parsed) return parsed.error();
    options.level = unsigned(*parsed);
  }
  auto bias = single(params, "bias");
  if (!bias) return bias.error();
  if (*bias) {
    auto parsed = parse_finite_number(**bias, "bias");
    if (!parsed) return parsed.error();
    if (*parsed < 0) return invalid("parameter 'bias' must be >= 0");
    options.bias = *parsed;
  }
  return options;
}

Result<Vec3> point_from_params(const Params& params) {
  Vec3 point{};
  static const std::string kNames[3] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    auto text = single(params, kNames[axis]);
    if (!text) return text.error();
    if (!*text) return invalid("parameter '" + kNames[axis] + "' is missing (give x, y and z)");
    auto value = parse_finite_number(**text, kNames[axis]);
    if (!value) return value.error();
    point[axis] = *value;
  }
  return point;
}

Result<QueryOptions> options_from_json(const nlohmann::json& options, unsigned max_pcf) {
  if (!options.is_object()) return invalid("the body must be a JSON object {\"points\": [[x, y, z], ...]}");
  QueryOptions result;
  for (const auto& [key, value] : options.items()) {
    if (key == "pcf") {
      if (!value.is_number_integer() || (!value.is_number_unsigned() && value.get<int64_t>() < 0))
        return invalid("\"pcf\" must be an odd positive integer");
      if (Status s = check_pcf(value.get<uint64_t>(), max_pcf); !s) return s.error();
      result.pcf = unsigned(value.get<uint64_t>());
    } else if (key == "method") {
      if (!value.is_string()) return invalid("\"method\" must be a string");
      auto parsed = method_named(value.get_ref<const std::string&>());
      if (!parsed) return parsed.error();
      result.method = *parsed;
    } else if (key == "level") {
      if (!value.is_number_unsigned() || value.get<uint64_t>() > 255)
        return invalid("\"level\" must be an integer in [0, 255]");
      result.level = unsigned(value.get<uint64_t>());
    } else if (key == "bias") {
      if (!value.is_number() || !std::isfinite(value.get<double>()) || value.get<double>() < 0)
        return invalid("\"bias\" must be a finite number >= 0");
      result.bias = value.get<double>();
    } else {
      return invalid("unknown key " + shown(key) + " (known: points, pcf, method, level, bias)");
    }
  }
  return result;
}

namespace {

// SAX handler for a batch body. Depth 1 = the top object, 2 = the points array, 3 = one point.
// Every event outside the expected shape stops the parse with a message.
class BatchSax {
 public:
  using json = nlohmann::json;
  explicit BatchSax(uint64_t max_points) : max_points_(max_points) {}

  bool null() { return scalar(nullptr); }
  bool boolean(bool v) { return scalar(v); }
  bool number_integer(json::number_integer_t v) { return number(double(v), json(v)); }
  bool number_unsigned(json::number_unsigned_t v) { return number(double(v), json(v)); }
  bool number_float(json::number_float_t v, const json::string_t&) { return number(v, json(v)); }
  bool string(json::string_t& v) { return scalar(v); }
  bool binary(json::binary_t&) { return fail("unexpected binary value"); }
  bool start_object(std::size_t) {
    if (depth_ != 0) return fail(depth_ == 1 ? "option " + shown(key_) + " must be a number or string"
                                             : "points must be arrays of 3 numbers");
    depth_ = 1;
    return true;
  }
  bool key(json::string_t& k) {
    if (k == "points" && seen_points_) return fail("\"points\" is given more than once");
    if (k != "points" && options_.contains(k)) return fail("key " + shown(k) + " is given more than once");
    key_ = k;
    return true;
  }
  bool end_object() {
    depth_ = 0;
    return true;
  }
  bool start_array(std::size_t) {
    if (depth_ == 1 && key_ == "points") {
      seen_points_ = true;
      depth_ = 2;
      return true;
    }
    if (depth_ == 2) {
      depth_ = 3;
      axis_ = 0;
      return true;
    }
    if (depth_ == 0) return fail("the body must be a JSON object {\"points\": [[x, y, z], ...]}");
    if (depth_ == 1) return fail("option " + shown(key_) + " must be a number or string");
    return fail("points[" + std::to_string(points_.size()) + "] must be an array of 3 numbers");
  }
  bool end_array() {
    if (depth_ == 3) {
      if (axis_ != 3) return fail("points[" + std::to_string(points_.size()) + "] must be an array of 3 numbers");
      if (points_.size() >= max_points_) {
        too_many_ = true;
        return fail("more than " + std::to_string(max_points_) + " points in one batch");
      }
      points_.push_back(point_);
      depth_ = 2;
      return true;
    }
    depth_ = 1;  // end of "points"
    return true;
  }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception&) {
    return fail("body is not valid JSON (at byte " + std::to_string(position) + ")");
  }

  Result<JsonBatch> finish(bool parsed, unsigned max_pcf) {
    if (!parsed || !message_.empty())
      return make_error(too_many_ ? ErrorCode::out_of_space : ErrorCode::invalid_input,
                        message_.empty() ? "body is not a valid batch" : message_);
    if (!seen_points_) return invalid("\"points\" is missing: give {\"points\": [[x, y, z], ...]}");
    auto options = options_from_json(options_, max_pcf);
    if (!options) return options.error();
    return JsonBatch{std::move(points_), *options};
  }

 private:
  bool fail(std::string message) {
    if (message_.empty()) message_ = std::move(message);
    return false;
  }
  bool number(double value, json as_json) {
    if (depth_ != 3) return scalar(std::move(as_json));
    if (axis_ >= 3 || !std::isfinite(value))
      return fail("points[" + std::to_string(points_.size()) + "] must hold exactly 3 finite numbers");
    point_[axis_++] = value;
    return true;
  }
  bool scalar(json value) {
    if (depth_ == 1 && key_ != "points") {
      options_[key_] = std::move(value);
      return true;
    }
    if (depth_ == 1) return fail("\"points\" must be an array of [x, y, z] arrays");
    if (depth_ == 0) return fail("the body must be a JSON object {\"points\": [[x, y, z], ...]}");
    return fail("points[" + std::to_string(points_.size()) + "] must be an array of 3 numbers");
  }

  uint64_t max_points_;
  int depth_ = 0;
  std::string key_;
  bool seen_points_ = false;
  bool too_many_ = false;
  std::vector<Vec3> points_;
  Vec3 point_{};
  unsigned axis_ = 0;
  json options_ = json::object();
  std::string message_;
};

}  // namespace

Result<JsonBatch> parse_json_batch(std::string_view body, unsigned max_pcf, uint64_t max_points) {
  BatchSax sax(max_points);
  bool parsed = false;
  try {
    parsed = nlohmann::json::sax_parse(body, &sax, nlohmann::json::input_format_t::json, /*strict=*/true);
  } catch (const std::exception&) {
    parsed = false;  // nlohmann may still throw on a few malformed inputs; never let it escape
  }
  return sax.finish(parsed, max_pcf);
}

Result<std::vector<Vec3>> points_from_binary(std::span<const uint8_t> body) {
  if (body.size() % 12 != 0)
    return invalid("binary body of " + std::to_string(body.size()) +
                   " bytes is not a whole number of float32 x, y, z triples (12 bytes each)");
  std::vector<Vec3> points(body.size() / 12);
  for (size_t i = 0; i < points.size(); ++i) {
    for (size_t axis = 0; axis < 3; ++axis) {
      const uint8_t* b = body.data() + i * 12 + axis * 4;
      // Assembled byte by byte: little-endian on the wire whatever the host order.
      uint32_t bits = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
      float value = std::bit_cast<float>(bits);
      if (!std::isfinite(value))
        return invalid("point " + std::to_string(i) + " has a non-finite coordinate");
      points[i][axis] = double(value);
    }
  }
  return points;
}

}  // namespace shadowtiles::server
