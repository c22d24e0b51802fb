// xxHash64 of a file's bytes, streamed: part of a build's config hash so a changed scene file is
// never resumed into an old store.
#pragma once

#include <cstdint>
#include <filesystem>

#include "common/result.hpp"

namespace shadowtiles {
Result<uint64_t> hash_file(const std::filesystem::path& path);
}
