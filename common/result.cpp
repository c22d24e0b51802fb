#include "common/result.hpp"

namespace shadowtiles {

const char* error_code_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::invalid_input: return "invalid_input";
    case ErrorCode::corrupt_data: return "corrupt_data";
    case ErrorCode::not_found: return "not_found";
    case ErrorCode::io_error: return "io_error";
    case ErrorCode::out_of_space: return "out_of_space";
    case ErrorCode::unsupported: return "unsupported";
  }
  return "unknown";
}

}  // namespace shadowtiles
