#include "builder/builder_version.hpp"

namespace shadowtiles {
const char* builder_version() { return "shadowtiles-builder 0.2.0"; }
}  // namespace shadowtiles
