#include "builder/file_hash.hpp"

#include <xxhash.h>

#include <fstream>
#include <memory>
#include <vector>

namespace shadowtiles {

Result<uint64_t> hash_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::not_found, "cannot open " + path.string());
  std::unique_ptr<XXH64_state_t, decltype(&XXH64_freeState)> state(XXH64_createState(), XXH64_freeState);
  XXH64_reset(state.get(), 0);
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), std::streamsize(buffer.size()));
    XXH64_update(state.get(), buffer.data(), size_t(in.gcount()));
  }
  if (in.bad()) return make_error(ErrorCode::io_error, "read error on " + path.string());
  return uint64_t(XXH64_digest(state.get()));
}

}  // namespace shadowtiles
