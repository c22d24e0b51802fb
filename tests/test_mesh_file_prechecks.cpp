// The PLY and OFF checks in front of assimp (builder/mesh_file_prechecks.hpp): hostile headers and
// counts fail with a clear error before assimp hangs or allocates, and every real file still passes.
#include "builder/mesh_file_prechecks.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "builder/scene_loader.hpp"
#include "tests/testing_support.hpp"

// assimp's PLY importer leaks its parse tree on files that end early (builder/scene_loader.hpp).
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

namespace shadowtiles {
namespace {

using testing::assimp_model;
using testing::shared_scene;
using testing::TempDir;
using testing::write_file;


Scene load_ok(const std::filesystem::path& file) {
  auto scene = load_scene(file, {});
  EXPECT_TRUE(scene.ok()) << file << ": " << (scene.ok() ? "" : scene.error().message);
  return scene.ok() ? std::move(scene).value() : Scene{};
}

// The load fails with invalid_input and a message holding `needle`.
void expect_refused(const std::filesystem::path& file, const std::string& needle) {
  auto scene = load_scene(file, {});
  ASSERT_FALSE(scene.ok()) << file;
  EXPECT_EQ(scene.error().code, ErrorCode::invalid_input) << scene.error().message;
  EXPECT_NE(scene.error().message.find(needle), std::string::npos) << scene.error().message;
  EXPECT_NE(scene.error().message.find(file.filename().string()), std::string::npos) << scene.error().message;
}

template <typename T>
void append(std::string* out, T value, bool big_endian = false) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian)
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  out->append(bytes, sizeof(T));
}

// One triangle as a binary PLY whose face list count is `count` (of type `count_type`).
std::string binary_triangle(const char* count_type, uint32_t count, bool big_endian = false) {
  std::string f = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list " + count_type + " int vertex_indices\nend_header\n";
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  for (float v : xyz) append(&f, v, big_endian);
  if (std::string(count_type) == "uchar") f += char(uint8_t(count));
  else append(&f, count, big_endian);
  for (int32_t i : {0, 1, 2}) append(&f, i, big_endian);
  return f;
}

const std::string kAsciiHeader =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kAsciiVertices = "0 0 0\n1 0 0\n0 1 0\n";

TEST(MeshFilePrechecks, BinaryListCountBeyondTheFileIsRefused) {
  // fuzz_scene_loader regression (ply-binary-list-count-4e9): assimp 5.2 resizes a list to its
  // count before reading it, so a 4-byte count of ~4e9 in a 160-byte file asked for 32 GB.
  TempDir dir;
  for (bool big_endian : {false, true}) {
    const auto path = dir.path() / (big_endian ? "huge_list_be.ply" : "huge_list_le.ply");
    write_file(path, binary_triangle("uint", 0xFFFFFFF0u, big_endian));
    expect_refused(path, "list of 4294967280 items");
    write_file(path, binary_triangle("uint", 3, big_endian));
    EXPECT_EQ(load_ok(path).triangle_count(), 1u) << big_endian;
  }
  // A signed count that is negative.
  write_file(dir.path() / "negative.ply", binary_triangle("int", 0xFFFFFFFFu));
  expect_refused(dir.path() / "negative.ply", "negative list count");
  // One item more than the file holds is already refused (the bound is exact).
  write_file(dir.path() / "one_more.ply", binary_triangle("uint", 4));
  expect_refused(dir.path() / "one_more.ply", "cannot fit in the 12 bytes left");
}

TEST(MeshFilePrechecks, AsciiListCountBeyondItsLineIsRefused) {
  // fuzz_scene_loader regression (ply-ascii-list-count-4e9): the same allocation from a text count.
  TempDir dir;
  write_file(dir.path() / "huge_list.ply", kAsciiHeader + kAsciiVertices + "4000000000 0 1 2\n");
  expect_refused(dir.path() / "huge_list.ply", "a list of 4000000000 items on a line that holds 3 more words");
  write_file(dir.path() / "ok.ply", kAsciiHeader + kAsciiVertices + "3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "ok.ply").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, AsciiShortLinesAndFractionalCountsAreRefused) {
  // fuzz_scene_loader regression (ply-ascii-vertex-line-of-two-words): vertex line "0.000 30.000"
  // of an 81-vertex PLY; assimp 5.2 read on past the line and asked for 16 GB.
  TempDir dir;
  write_file(dir.path() / "short_line.ply", kAsciiHeader + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n");
  expect_refused(dir.path() / "short_line.ply", "element 'vertex' #1 (body line 2): 2 words for 3 properties");
  // A face line with its count and no room for the list's first index is caught the same way.
  write_file(dir.path() / "bare_count.ply", kAsciiHeader + kAsciiVertices + "3\n");
  expect_refused(dir.path() / "bare_count.ply", "a list of 3 items on a line that holds 0 more words");
  // fuzz_scene_loader regression (ply-ascii-list-count-with-a-fraction): assimp 5.2 reads the
  // leading digits of "123333333330.000" as the count and took 2.2 GB.
  write_file(dir.path() / "fraction.ply", kAsciiHeader + kAsciiVertices + "123333333330.000 0 1 2\n");
  expect_refused(dir.path() / "fraction.ply", "list count '123333333330.000' is not a plain integer");
  write_file(dir.path() / "three_point_oh.ply", kAsciiHeader + kAsciiVertices + "3.0 0 1 2\n");
  expect_refused(dir.path() / "three_point_oh.ply", "list count '3.0' is not a plain integer");
  // Words beyond the properties are left to assimp, which ignores them.
  write_file(dir.path() / "long_line.ply", kAsciiHeader + "0 0 0 7\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "long_line.ply").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, TruncatedBinaryBodyIsRefused) {
  TempDir dir;
  // Cut inside the face list: the header's minimum-size rule still passes (the count byte is there).
  const std::string full = binary_triangle("uchar", 3);
  write_file(dir.path() / "cut.ply", full.substr(0, full.size() - 4));
  expect_refused(dir.path() / "cut.ply", "a list of 3 items (12 bytes) cannot fit in the 8 bytes left");
  // Faces first, then vertices cut short: 43 body bytes pass the minimum (37), the walk finds 30 of 36.
  std::string faces_first =
      "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  faces_first += char(3);
  for (int32_t i : {0, 1, 2}) append(&faces_first, i);
  faces_first += std::string(30, '\0');
  write_file(dir.path() / "short.ply", faces_first);
  expect_refused(dir.path() / "short.ply", "the body ends inside element 'vertex'");
}

TEST(MeshFilePrechecks, ShortAsciiBodyIsRefused) {
  // fuzz_scene_loader regression (ply-ascii-body-shorter-than-declared): 81 vertices and 128 faces
  // declared, 113 lines given; assimp 5.2 read on past the end and took 21 GB before the kernel killed it.
  TempDir dir;
  write_file(dir.path() / "short.ply", kAsciiHeader + kAsciiVertices);  // the face line is missing
  expect_refused(dir.path() / "short.ply", "truncated");
  std::string padded = kAsciiHeader + kAsciiVertices;
  padded.replace(padded.find("element face 1"), 14, "element face 2");
  write_file(dir.path() / "padded.ply", padded + "3 0 1 2\n" + std::string(64, ' '));  // passes the size rule
  expect_refused(dir.path() / "padded.ply", "the body ends at element 'face' #1 of 2 (truncated file)");
  // Blank lines are skipped, as assimp does.
  write_file(dir.path() / "blank.ply", kAsciiHeader + "0 0 0\n\n1 0 0\n0 1 0\n\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "blank.ply").triangle_count(), 1u);
}

// The one-triangle ascii PLY with `from` in its header replaced by `to`, written to dir/name.
std::filesystem::path edited_ascii_ply(const TempDir& dir, const std::string& name, const std::string& from,
                                       const std::string& to) {
  std::string header = kAsciiHeader;
  header.replace(header.find(from), from.size(), to);
  write_file(dir.path() / name, header + kAsciiVertices + "3 0 1 2\n");
  return dir.path() / name;
}

TEST(MeshFilePrechecks, HeaderTypesAndFormatMustBePly) {
  TempDir dir;
  expect_refused(edited_ascii_ply(dir, "type.ply", "property float z", "property quux z"),
                 "unknown property type 'quux'");
  expect_refused(edited_ascii_ply(dir, "format.ply", "ascii", "binary_middle_endian"), "unknown format");
  expect_refused(edited_ascii_ply(dir, "float_count.ply", "list uchar", "list float"), "not an integer type");
}

TEST(MeshFilePrechecks, ElementNamesStartingWithADigitAreRefused) {
  // assimp 5.2 took the count of an unknown element from its name's leading digits (fuzz_scene_loader:
  // "element 2222...face 128" asked for 57 GB); "7face" still loads with that rule, so the digit
  // itself is refused.
  TempDir dir;
  expect_refused(edited_ascii_ply(dir, "digits.ply", "element face", "element 22222222222face"),
                 "starts with a digit");
  // A name with a digit inside is fine (an element assimp does not know: no instances for either).
  const auto named = edited_ascii_ply(dir, "named.ply", "element face", "element face2");
  EXPECT_TRUE(check_ply_file(named, std::filesystem::file_size(named)).ok());
}

TEST(MeshFilePrechecks, LineBreaksTheImporterSeesAreTheChecksToo) {
  // assimp 5.2 also ends a line at \r and \f and joins a line ending in a backslash with the next:
  // a \r inside a face line made it read "88888888888888888888 ..." as a face (fuzz_scene_loader,
  // gigabytes). Such bodies are refused; CRLF line ends are fine.
  TempDir dir;
  write_file(dir.path() / "cr.ply", kAsciiHeader + kAsciiVertices + "3 0 1\r88888888888888888888 2\n");
  expect_refused(dir.path() / "cr.ply", "carriage return or form feed inside a line");
  write_file(dir.path() / "backslash.ply", kAsciiHeader + kAsciiVertices + "3 0 1 2 \\\n");
  expect_refused(dir.path() / "backslash.ply", "ending in a backslash");
  write_file(dir.path() / "cr.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\f2\n");
  expect_refused(dir.path() / "cr.off", "carriage return or form feed inside a line");
  write_file(dir.path() / "cr_counts.off", "OFF\n3 1\r0 0 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_refused(dir.path() / "cr_counts.off", "carriage return or form feed inside a line");
  // An element line hidden in a comment for the check, a line of its own for assimp.
  expect_refused(edited_ascii_ply(dir, "header_cr.ply", "element face 1", "comment x\relement face 1"),
                 "carriage return inside a header line");
  // assimp drops "property float z" after the comment.
  expect_refused(
      edited_ascii_ply(dir, "comment_inside.ply", "property float z", "comment z follows\nproperty float z"),
      "after a comment or blank line inside an element");
  std::string crlf = kAsciiHeader;  // the body's lines end in \r\n
  for (char c : kAsciiVertices + "3 0 1 2\n") {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  write_file(dir.path() / "crlf.ply", crlf);
  EXPECT_EQ(load_ok(dir.path() / "crlf.ply").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, ElementsTheImporterDoesNotKnowHaveNoInstances) {
  // assimp 5.2 gives an element it does not know (here "camera") no instances, so the 4 bytes the
  // header gives it are the face's list count for assimp: 0xfffffff0, a 64 GB list. The walk follows
  // assimp and refuses the count.
  TempDir dir;
  std::string f =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement camera 1\nproperty uint a\nelement face 1\n"
      "property list uint int vertex_indices\nend_header\n";
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append(&f, v);
  append(&f, uint32_t(0xfffffff0u));  // the camera's value, assimp's face count
  append(&f, uint32_t(3));
  for (int32_t i : {0, 1, 2}) append(&f, i);
  write_file(dir.path() / "camera.ply", f);
  expect_refused(dir.path() / "camera.ply", "cannot fit");
  // In ascii the unknown element's line is read as the first vertex, by assimp and by the walk.
  write_file(dir.path() / "camera_ascii.ply",
             "ply\nformat ascii 1.0\nelement camera 1\nproperty float a\nelement vertex 3\nproperty float x\n"
             "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n7 7 7\n0 0 0\n1 0 0\n3 0 1 2\n");
  const Scene scene = load_ok(dir.path() / "camera_ascii.ply");
  ASSERT_EQ(scene.vertices.size(), 3u);
}

TEST(MeshFilePrechecks, OffCountsMustBeIntegers) {
  // fuzz_scene_loader regression (off-vertex-count-then-vertex-line): no face count, then a vertex line
  // after a 13-digit vertex count; assimp 5.2 took 60 (from "60.000") as the face count and wrapped the
  // vertex count to 32 bits: a 10.5 GB allocation from an 856-byte file.
  TempDir dir;
  write_file(dir.path() / "wrapped.off", "OFF\n6666666666653\n60.000 120.000 242.186\n90.000 120.000 245.388\n");
  expect_refused(dir.path() / "wrapped.off",
                 "the header must give the vertex and face counts as integers (found '60.000')");
  write_file(dir.path() / "missing.off", "OFF\n3\n");
  expect_refused(dir.path() / "missing.off", "the header must give the vertex and face counts as integers (found '3')");
  // fuzz_scene_loader regression (off-keyword-glued-to-a-comment): "OFF#81 128 00 ..." passed as the
  // keyword OFF and counts 128 and 0, while assimp 5.2 read it otherwise and crashed (SEGV).
  write_file(dir.path() / "glued.off", "OFF#81 128 00 60.000 197.849\n3 0 1 2\n");
  expect_refused(dir.path() / "glued.off", "unknown header keyword 'OFF#81'");
  write_file(dir.path() / "coff.off", "COFF\n3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "coff.off").triangle_count(), 1u);
  write_file(dir.path() / "ok.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "ok.off").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, OffWithoutItsKeywordLineIsRefused) {
  // fuzz_scene_loader regression (off-body-without-its-keyword-line): counts and body lines that our
  // check accepted, but without the "OFF" line assimp 5.2 read them otherwise, dropped faces and read
  // out of bounds (SEGV).
  TempDir dir;
  const std::string body = "3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  write_file(dir.path() / "bare.off", body);
  expect_refused(dir.path() / "bare.off", "must start with its keyword line");
  write_file(dir.path() / "commented.off", "# a comment first\n\n" + body);
  expect_refused(dir.path() / "commented.off", "found '3'");
  write_file(dir.path() / "keyword.off", "# a comment first\nOFF\n" + body);
  EXPECT_EQ(load_ok(dir.path() / "keyword.off").triangle_count(), 1u);
  write_file(dir.path() / "same_line.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "same_line.off").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, NulByteInAnAsciiBodyIsRefused) {
  // fuzz_scene_loader regression (ply-ascii-nul-byte-in-body): assimp 5.2 reads an ascii body as a C
  // string, so a NUL byte ends it early and the importer read on past the end (over 2 GB).
  TempDir dir;
  const std::string ply_header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  write_file(dir.path() / "nul.ply", ply_header + "0 0 0\n1 0 0\n0 1" + std::string(1, '\0') + "0\n3 0 1 2\n");
  expect_refused(dir.path() / "nul.ply", "a NUL byte in the ascii body");
  write_file(dir.path() / "nul.off", "OFF\n3 1 0\n0 0 0\n1 0" + std::string(1, '\0') + " 0\n0 1 0\n3 0 1 2\n");
  expect_refused(dir.path() / "nul.off", "a NUL byte in the body");
  write_file(dir.path() / "ok.ply", ply_header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "ok.ply").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, OffFaceOfNoVertexIsRefused) {
  // fuzz_scene_loader regression (off-face-of-no-vertex): the one face of an 81-vertex file was "0 255.283";
  // assimp 5.2 drops such a face, keeps the mesh with fewer faces than it allocated, and crashed (SEGV).
  TempDir dir;
  write_file(dir.path() / "empty-face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n0 255.283\n");
  expect_refused(dir.path() / "empty-face.off", "face #0 has no vertices");
  write_file(dir.path() / "ok.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "ok.off").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, OffFacesMustNameTheirVertices) {
  // fuzz_scene_loader regression (off-face-count-beyond-its-line): assimp 5.2 reads a face's indices
  // without checking them; a face line "90.000 240.000 373.413" (a vertex line where a face was
  // expected) made it read far out of bounds and crash.
  TempDir dir;
  const std::string header = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n";
  write_file(dir.path() / "range.off", header + "3 0 1 5\n");
  expect_refused(dir.path() / "range.off", "face #0: vertex index 5 is out of range (the file has 3 vertices)");
  write_file(dir.path() / "short.off", header + "90 1 2\n");
  expect_refused(dir.path() / "short.off", "face #0 declares 90 vertices and lists 2");
  write_file(dir.path() / "float.off", header + "90.000 240.000 373.413\n");
  expect_refused(dir.path() / "float.off", "face #0 does not start with its vertex count ('90.000')");
  write_file(dir.path() / "word.off", header + "3 0 x 2\n");
  expect_refused(dir.path() / "word.off", "face #0: 'x' is not a vertex index");
  // Blank lines are skipped (as assimp does); colour values after the indices are allowed.
  write_file(dir.path() / "ok.off", "OFF 3 1 0\n0 0 0\n\n1 0 0\n0 1 0\n3 0 1 2 255 0 0\n");
  EXPECT_EQ(load_ok(dir.path() / "ok.off").triangle_count(), 1u);
  for (const char* model : {"OFF/Cube.off", "OFF/Wuson.off"}) {
    const auto path = assimp_model(model);
    auto status = check_off_file(path, std::filesystem::file_size(path));
    EXPECT_TRUE(status.ok()) << model << ": " << (status.ok() ? "" : status.error().message);
  }
}

TEST(MeshFilePrechecks, EveryRealPlyPasses) {
  // Ascii (dragon) and binary (honolulu, oahu, terragen) scenes, and assimp's own test models.
  for (const char* scene : {"dragon_res2/dragon_vrip_res2.ply", "honolulu_airport/honolulu_airport_harbour.ply",
                            "oahu/oahu_w158n21.ply", "terragen/RealisticTerrain.ply"}) {
    const auto path = shared_scene(scene);
    EXPECT_TRUE(check_ply_file(path, std::filesystem::file_size(path)).ok()) << scene;
  }
  for (const char* model : {"PLY/cube.ply", "PLY/cube_binary.ply", "PLY/cube_uv.ply", "PLY/float-color.ply",
                            "PLY/issue623.ply", "PLY/points.ply"}) {
    const auto path = assimp_model(model);
    auto status = check_ply_file(path, std::filesystem::file_size(path));
    EXPECT_TRUE(status.ok()) << model << ": " << (status.ok() ? "" : status.error().message);
  }
  // Two of assimp's test models are refused, on purpose: Wuson.ply has a header line that is no PLY
  // keyword ("Created by Blender3D ..."; unknown lines make assimp 5.2 seek for seconds), and
  // pond.0.ply is 69 bytes shorter than its header declares.
  expect_refused(assimp_model("PLY/Wuson.ply"), "unknown header keyword 'Created'");
  expect_refused(assimp_model("PLY/pond.0.ply"), "truncated or corrupt");
}

TEST(MeshFilePrechecks, CountsBeyondTheFileSizeAreRejectedUpFront) {
  // assimp would allocate and walk billions of elements (minutes, gigabytes) before failing.
  TempDir dir;
  write_file(dir.path() / "huge.ply",
             "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty float x\n"
             "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n" +
                 std::string(100, '\0'));
  write_file(dir.path() / "huge.off", "OFF\n3 2000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  for (const char* name : {"huge.ply", "huge.off"}) {
    auto scene = load_scene(dir.path() / name, {});
    ASSERT_FALSE(scene.ok()) << name;
    EXPECT_EQ(scene.error().code, ErrorCode::invalid_input) << name;
  }
  write_file(dir.path() / "ok.off", "OFF\n# comment\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_ok(dir.path() / "ok.off").triangle_count(), 1u);
}

TEST(MeshFilePrechecks, ControlCharacterInPlyHeaderIsRefused) {
  // fuzz_scene_loader regression: "end_header" followed by a vertical tab passed the header check
  // (isspace) while assimp 5.2 never saw the header end and seeked for ever.
  TempDir dir;
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  for (const std::string& bad : {std::string("\v"), std::string("\f"), std::string(1, '\0'), std::string("\x01")}) {
    std::string file = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header";
    file += bad;
    file += body;
    write_file(dir.path() / "vtab.ply", file);
    auto scene = load_scene(dir.path() / "vtab.ply", {});
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.error().code, ErrorCode::invalid_input);
    EXPECT_NE(scene.error().message.find("control character"), std::string::npos) << scene.error().message;
  }
  // fuzz_scene_loader regression: an unknown header line made assimp seek for 32 s on 1.6 KB.
  write_file(dir.path() / "unknown.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\npr$clr.specularoperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n" + body);
  auto unknown = load_scene(dir.path() / "unknown.ply", {});
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("unknown header keyword 'pr$clr.specularoperty'"), std::string::npos)
      << unknown.error().message;
  // The same file with a plain newline still loads.
  write_file(dir.path() / "ok.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\r\n" + body);
  EXPECT_EQ(load_ok(dir.path() / "ok.ply").triangle_count(), 1u);
}

}  // namespace
}  // namespace shadowtiles
