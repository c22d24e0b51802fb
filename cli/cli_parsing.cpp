#include "cli/cli_parsing.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace shadowtiles::cli {

Result<std::vector<double>> parse_numbers(const std::string& text, size_t count, const std::string& what) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    char* end = nullptr;
    double value = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0' || !std::isfinite(value))
      return make_error(ErrorCode::invalid_input, what + ": '" + item + "' is not a finite number");
    values.push_back(value);
  }
  if (values.size() != count || (!text.empty() && text.back() == ','))
    return make_error(ErrorCode::invalid_input,
                      what + ": expected " + std::to_string(count) + " comma-separated numbers, got '" + text + "'");
  return values;
}

Result<Vec3> parse_vec3(const std::string& text, const std::string& what) {
  auto values = parse_numbers(text, 3, what);
  if (!values) return values.error();
  return Vec3{(*values)[0], (*values)[1], (*values)[2]};
}

Result<UpAxis> parse_up_axis(const std::string& text) {
  if (text == "z") return UpAxis::z;
  if (text == "y") return UpAxis::y;
  return make_error(ErrorCode::invalid_input, "--up must be 'z' or 'y', got '" + text + "'");
}

}  // namespace shadowtiles::cli
