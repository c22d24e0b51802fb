// Fuzz target: the scene loader's own code on hostile files (builder/scene_loader.hpp): the PLY and
// OFF header pre-checks that stop assimp from hanging or allocating gigabytes, the Terragen (.ter)
// reader, and the conversion of whatever assimp returns (index checks, transforms, classification).
// The first input byte picks the extension (.ply, .off, .ter); the rest is the file, written to a
// per-process temporary file. assimp itself is not instrumented (Debian's library). Inputs the
// pre-checks refuse never construct an assimp Importer (scene_loader.cpp checks first), so most
// executions cost one small file write and one read.
// Invariant: no crash, an error has a message, an accepted scene has finite bounds and triangles.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <spdlog/spdlog.h>

#include "builder/scene_loader.hpp"
#include "fuzz/fuzz_check.hpp"

using namespace shadowtiles;

namespace {

// In memory (/dev/shm) unless TMPDIR says otherwise: a file is written and removed per input.
std::filesystem::path temp_file(const char* extension) {
  const char* dir = std::getenv("TMPDIR");
  std::error_code ec;
  const char* base = dir && *dir ? dir : std::filesystem::is_directory("/dev/shm", ec) ? "/dev/shm" : "/tmp";
  return std::filesystem::path(base) / ("shadowtiles-fuzz-" + std::to_string(::getpid()) + extension);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".ply", ".off", ".ter"};
  const auto path = temp_file(kExtensions[data[0] % 3]);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
  }
  LoadOptions options;
  options.heightfield_meshes = (data[0] & 4) ? std::vector<std::string>{"*"} : std::vector<std::string>{};
  auto scene = load_scene(path, options);
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
  if (!scene) {
    FUZZ_CHECK(!scene.error().message.empty());
    return 0;
  }
  FUZZ_CHECK(scene->triangle_count() > 0);
  return 0;
}
