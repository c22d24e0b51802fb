// CPVS serialisation: an in-memory DAG (builder/cpvs_dag_builder.hpp) -> the payload bytes of
// codec/cpvs_format.hpp. Refs are byte offsets into the next level (or leaf indices), each level
// with the narrowest ref width (1..4 bytes) its targets need.
// Errors: invalid_input when a level would exceed 4 GiB or the DAG is inconsistent.
// Thread safety: stateless.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/cpvs_dag_builder.hpp"
#include "common/result.hpp"

namespace shadowtiles {

Result<std::vector<uint8_t>> serialize_cpvs_dag(const CpvsDag& dag);

}  // namespace shadowtiles
