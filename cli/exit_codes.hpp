// Documented exit codes of `shadowtiles` (README "Options reference"):
//   0 success; 1 runtime failure (I/O, Embree, out of space); 2 invalid input (bad flags, malformed or
//   unsupported scene, bad query); 3 a check failed (verify found texels outside their interval);
//   4 the store is corrupt (blob or meta fails its checks).
#pragma once

#include "common/result.hpp"

namespace shadowtiles::cli {

enum ExitCode : int { kOk = 0, kFailure = 1, kInvalidInput = 2, kCheckFailed = 3, kCorruptStore = 4 };

inline int exit_code_for(const Error& error) {
  switch (error.code) {
    case ErrorCode::invalid_input:
    case ErrorCode::not_found:
    case ErrorCode::unsupported: return kInvalidInput;
    case ErrorCode::corrupt_data: return kCorruptStore;
    case ErrorCode::io_error:
    case ErrorCode::out_of_space: return kFailure;
  }
  return kFailure;
}

}  // namespace shadowtiles::cli
