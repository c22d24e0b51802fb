// Checks a PLY or OFF file before assimp 5.2 parses it, so that hostile or corrupt files fail with
// a clear error instead of making assimp hang or allocate gigabytes (each rule below was found by the
// truncation tests, assimp-testmodels' "invalid" files, or fuzz_scene_loader; see
// fuzz/regressions/fuzz_scene_loader/).
//
// PLY (check_ply_file):
// - the header starts with the "ply" line and ends with "end_header" (a truncated header makes
//   assimp loop for ever);
// - the header holds only PLY keywords and no control characters (unknown lines and a vertical tab
//   after "end_header" make assimp seek for seconds or for ever);
// - property types are PLY's scalar types; element names do not start with a digit (assimp reads an
//   unknown element's count from the start of its name), and an element assimp does not know
//   (other than vertex, face, tristrips, edge, material) is walked with no instances, as assimp
//   reads it; no property follows a comment or blank line inside an element (assimp drops it); no
//   \r inside a header line (assimp ends lines there);
// - the body holds what the header declares: every element instance is walked (binary: by bytes,
//   ascii: one instance per line, as assimp reads them), and every list's item count must fit in
//   what is left (binary: of the file, ascii: of its line). assimp resizes a list to its count before
//   reading it, so a 4-byte count of 4e9 is a 32 GB allocation from a 200-byte file.
//   Bodies shorter than their header declares are refused as truncated (binary: by bytes; ascii: by
//   non-blank lines, since assimp 5.2 reads on past the end of a short ascii body).
// OFF (check_off_file): the vertex and face counts must fit in the file (a vertex takes at least
// "0 0 0\n", a face "0\n"); every face line starts with its vertex count, lists that many indices,
// and each index names a vertex (assimp 5.2 reads them unchecked: out-of-bounds reads, a crash).
// Other oddities (short files, bad numbers in vertex lines) are left to assimp's own errors.
//
// Cost: one sequential read of the file (binary lists are walked per instance; elements without
// lists are skipped in one step), small next to assimp's own parse.
// Errors: invalid_input with the file name, the format and the rule that failed; io_error when the
// file cannot be read.
#pragma once

#include <cstdint>
#include <filesystem>

#include "common/result.hpp"

namespace shadowtiles {

Status check_ply_file(const std::filesystem::path& file, uint64_t file_size);
Status check_off_file(const std::filesystem::path& file, uint64_t file_size);

}  // namespace shadowtiles
