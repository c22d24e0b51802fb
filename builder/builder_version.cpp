#include "builder/builder_version.hpp"

namespace shadowtiles {
const char* builder_version() { return "shadowtiles-builder 0.3.5"; }
}  // namespace shadowtiles
