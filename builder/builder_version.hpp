// The builder's version: part of every build's config hash, so a store built by an older builder
// is never resumed by a newer one.
#pragma once

namespace shadowtiles {
const char* builder_version();
}
