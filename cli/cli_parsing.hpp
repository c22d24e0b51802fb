// Parsing of the CLI's compound values ("AZ,EL", "X,Y,Z") with clear errors.
#pragma once

#include <string>
#include <vector>

#include "codec/light_frame.hpp"
#include "common/result.hpp"

namespace shadowtiles::cli {

// Exactly `count` comma-separated finite numbers.
Result<std::vector<double>> parse_numbers(const std::string& text, size_t count, const std::string& what);
Result<Vec3> parse_vec3(const std::string& text, const std::string& what);
Result<UpAxis> parse_up_axis(const std::string& text);

}  // namespace shadowtiles::cli
