#include "builder/mesh_file_prechecks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "builder/ply_scalar_types.hpp"

namespace shadowtiles {
namespace {

// The first `limit` bytes of `file` (fewer when the file is shorter: a buffer of the file's own size,
// not of `limit`, which a small file would pay zeroing).
std::string read_head(const std::filesystem::path& file, size_t limit) {
  std::error_code ec;
  const uint64_t file_size = std::filesystem::file_size(file, ec);
  std::ifstream in(file, std::ios::binary);
  std::string head(size_t(ec ? limit : std::min<uint64_t>(limit, file_size)), '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(size_t(std::max<std::streamsize>(0, in.gcount())));
  return head;
}

// Parses a non-negative decimal integer, saturating (the values are only compared with sizes).
bool parse_count(std::string_view text, uint64_t* value) {
  if (text.empty()) return false;
  uint64_t v = 0;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
    v = v > (UINT64_MAX - 9) / 10 ? UINT64_MAX : v * 10 + uint64_t(c - '0');
  }
  *value = v;
  return true;
}

// std::isspace in the C locale (the files are bytes, not text in the user's locale), inlined: the
// library call per byte was most of an ascii body's check.
bool is_space(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }

// Into `words` (cleared first): a body walk reuses one vector for every line rather than
// allocating one per line (a third of dragon's 300,000-line ascii check).
void split_words(std::string_view line, std::vector<std::string_view>& words) {
  words.clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  split_words(line, words);
  return words;
}

// assimp 5.2 ends a text line at \r, \n, \f or NUL, and joins a line ending in a backslash with the
// next; the checks read lines up to \n. A trailing \r (CRLF files) is dropped here; any other line
// break inside a line, or a continuation, is named (nullptr: none), since the importer would read
// that line otherwise than the check (found by fuzz_scene_loader: a \r inside a face line made
// assimp read the text after it as a face of 88888888888888888888 vertices, gigabytes).
const char* strip_line_end(std::string& line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line.find_first_of("\r\f") != std::string::npos) return "a carriage return or form feed inside a line";
  if (!line.empty() && line.back() == '\\') return "a line ending in a backslash (a continuation)";
  return nullptr;
}

uint64_t saturating_mul_add(uint64_t sum, uint64_t count, uint64_t size) {
  if (size != 0 && count > (UINT64_MAX - sum) / size) return UINT64_MAX;
  return sum + count * size;
}

// ---- PLY ----

struct PlyProperty {
  bool is_list = false;
  PlyScalarType count;  // lists only
  PlyScalarType value;  // the scalar, or a list's items
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  bool has_list() const {
    return std::any_of(properties.begin(), properties.end(), [](const PlyProperty& p) { return p.is_list; });
  }
  uint64_t fixed_bytes() const {  // binary bytes of one instance when it has no list
    uint64_t bytes = 0;
    for (const PlyProperty& p : properties) bytes += p.value.bytes;
    return bytes;
  }
};

enum class PlyFormat { ascii, binary_little_endian, binary_big_endian };

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  uint64_t body_offset = 0;
};

// Sequential reads of a file through a buffer, with skips that only seek.
class FileCursor {
 public:
  FileCursor(const std::filesystem::path& file, uint64_t offset, uint64_t size)
      : in_(file, std::ios::binary), position_(offset), size_(size) {}
  bool is_open() const { return bool(in_); }
  uint64_t left() const { return size_ - std::min(size_, position_); }
  void skip(uint64_t bytes) { position_ += bytes; }
  // Reads `bytes` (<= 8) at the cursor; false at the end of the file.
  bool read(void* out, size_t bytes) {
    if (left() < bytes) return false;
    if (position_ < buffer_start_ || position_ + bytes > buffer_start_ + buffer_.size()) {
      in_.clear();
      in_.seekg(std::streamoff(position_));
      buffer_.resize(kBufferBytes);
      in_.read(buffer_.data(), std::streamsize(buffer_.size()));
      buffer_.resize(size_t(std::max<std::streamsize>(0, in_.gcount())));
      buffer_start_ = position_;
      if (buffer_.size() < bytes) return false;
    }
    std::memcpy(out, buffer_.data() + (position_ - buffer_start_), bytes);
    position_ += bytes;
    return true;
  }

 private:
  static constexpr size_t kBufferBytes = 1 << 16;
  std::ifstream in_;
  std::vector<char> buffer_;
  uint64_t buffer_start_ = 0;
  uint64_t position_;
  uint64_t size_;
};

// A binary list count, in the file's byte order; nullopt for a negative count.
std::optional<uint64_t> decode_count(const unsigned char* bytes, PlyScalarType type, bool big_endian) {
  uint64_t v = 0;
  for (unsigned i = 0; i < type.bytes; ++i) {
    const unsigned byte = big_endian ? bytes[i] : bytes[type.bytes - 1 - i];
    v = (v << 8) | byte;
  }
  if (type.is_signed && (v >> (8 * type.bytes - 1)) != 0) return std::nullopt;
  return v;
}

class PlyChecker {
 public:
  PlyChecker(const std::filesystem::path& file, uint64_t file_size) : file_(file), file_size_(file_size) {}

  Status run() {
    if (Status ok = parse_header(); !ok) return ok;
    return header_.format == PlyFormat::ascii ? walk_ascii() : walk_binary();
  }

 private:
  Error fail(const std::string& why) const {
    return make_error(ErrorCode::invalid_input, fmt::format("{}: PLY: {}", file_.string(), why));
  }

  Status parse_header() {
    const std::string head = read_head(file_, 1 << 20);
    if (head.rfind("ply", 0) != 0 || head.size() < 4 || (head[3] != '\n' && head[3] != '\r'))
      return fail("missing the 'ply' magic line");
    uint64_t minimum = 0;  // bytes the declared elements need at least
    bool properties_interrupted = false;  // a comment or blank line since the last element line
    size_t pos = 0;
    while (pos < head.size()) {
      const size_t end = head.find('\n', pos);
      if (end == std::string::npos) break;
      const std::string_view line = std::string_view(head).substr(pos, end - pos);
      // assimp splits header words on spaces and tabs only and ends lines at \r, \n, \f or NUL: a
      // line "end_header\v..." passes a check that splits on isspace, then makes assimp 5.2 seek
      // for ever. The header is text: refuse any other control byte.
      for (char c : line)
        if ((static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\r') || c == 0x7f)
          return fail(fmt::format("control character 0x{:02x} in the header", static_cast<unsigned char>(c)));
      // assimp also ends a line at \r: "comment x\relement vertex 4000000000" is an element for it.
      if (const size_t cr = line.find('\r'); cr != std::string_view::npos && cr + 1 != line.size())
        return fail("a carriage return inside a header line");
      const auto words = split_words(line);
      pos = end + 1;
      // assimp ends an element's property list at the first other line (a comment, a blank line) and
      // drops the properties after it: a walk that kept them would check other bytes than it reads.
      const bool interruption = words.empty() || words[0] == "comment" || words[0] == "obj_info";
      if (interruption && !header_.elements.empty()) properties_interrupted = true;
      if (words.empty()) continue;
      if (words[0] == "property" && properties_interrupted)
        return fail("a property after a comment or blank line inside an element (the importer drops it)");
      if (words[0] == "element") properties_interrupted = false;
      // assimp 5.2 spends seconds of seeking per unknown header line (a 1.6 KB file took 32 s).
      static constexpr std::string_view kKeywords[] = {"ply",     "format",   "comment",   "obj_info",
                                                       "element", "property", "end_header"};
      if (std::find(std::begin(kKeywords), std::end(kKeywords), words[0]) == std::end(kKeywords))
        return fail(fmt::format("unknown header keyword '{}'", words[0].substr(0, 32)));
      if (words[0] == "format" && words.size() > 1) {
        if (words[1] == "ascii") header_.format = PlyFormat::ascii;
        else if (words[1] == "binary_little_endian") header_.format = PlyFormat::binary_little_endian;
        else if (words[1] == "binary_big_endian") header_.format = PlyFormat::binary_big_endian;
        else return fail(fmt::format("unknown format '{}'", words[1].substr(0, 32)));
      } else if (words[0] == "element" && words.size() > 2) {
        // assimp 5.2 reads the count of an element whose name it does not know from the start of the
        // name, not after it: "element 22222222222face 1" is 22 billion instances (found by
        // fuzz_scene_loader: a 57 GB allocation). PLY names are identifiers; a leading digit is refused.
        if (words[1][0] >= '0' && words[1][0] <= '9')
          return fail(fmt::format("element name '{}' starts with a digit", words[1].substr(0, 32)));
        PlyElement element;
        element.name = std::string(words[1].substr(0, 32));
        if (!parse_count(words[2], &element.count)) return fail("bad element count");
        // An element assimp 5.2 does not know has, for assimp, the count its name starts with: none
        // (an "element camera 1" before the vertices made it read the camera's line as the first
        // vertex). The walk follows assimp, or it checks other bytes than assimp reads (a binary
        // face count assimp takes from such an element's data: gigabytes).
        static constexpr std::string_view kKnown[] = {"vertex", "face", "tristrips", "edge", "material"};
        if (std::find(std::begin(kKnown), std::end(kKnown), words[1]) == std::end(kKnown)) element.count = 0;
        header_.elements.push_back(std::move(element));
      } else if (words[0] == "property" && words.size() > 2) {
        if (header_.elements.empty()) return fail("a property before any element");
        PlyProperty property;
        property.is_list = words[1] == "list";
        if (property.is_list) {
          if (words.size() < 4) return fail("a list property without its two types");
          property.count = ply_type(words[2]);
          property.value = ply_type(words[3]);
          if (property.count.bytes == 0 || property.value.bytes == 0)
            return fail(fmt::format("unknown list types '{} {}'", words[2].substr(0, 32), words[3].substr(0, 32)));
          if (!property.count.is_integer) return fail("a list count type that is not an integer type");
        } else {
          property.value = ply_type(words[1]);
          if (property.value.bytes == 0) return fail(fmt::format("unknown property type '{}'", words[1].substr(0, 32)));
        }
        header_.elements.back().properties.push_back(property);
      } else if (words[0] == "end_header") {
        header_.body_offset = pos;
        // Smallest encoding of one property: ascii "0 " = 2 bytes; binary: the scalar, or a list's count.
        for (const PlyElement& element : header_.elements) {
          uint64_t bytes = 0;
          for (const PlyProperty& p : element.properties)
            bytes += header_.format == PlyFormat::ascii ? 2 : (p.is_list ? p.count.bytes : p.value.bytes);
          minimum = saturating_mul_add(minimum, element.count, bytes);
        }
        const uint64_t body = file_size_ - std::min<uint64_t>(file_size_, pos);
        if (minimum > body)
          return fail(fmt::format(
              "the header declares at least {} bytes of data, the file has {} (truncated or corrupt)", minimum, body));
        return Status::success();
      }
    }
    return fail("header not terminated by an 'end_header' line (truncated file?)");
  }

  Status walk_binary() {
    FileCursor cursor(file_, header_.body_offset, file_size_);
    if (!cursor.is_open()) return make_error(ErrorCode::io_error, fmt::format("{}: cannot open", file_.string()));
    const bool big_endian = header_.format == PlyFormat::binary_big_endian;
    auto truncated = [&](const PlyElement& element, uint64_t instance) {
      return fail(fmt::format("the body ends inside element '{}' #{} of {} (truncated file)", element.name, instance,
                              element.count));
    };
    for (const PlyElement& element : header_.elements) {
      if (!element.has_list()) {  // fixed-size instances: one step
        const uint64_t bytes = saturating_mul_add(0, element.count, element.fixed_bytes());
        if (bytes > cursor.left()) return truncated(element, cursor.left() / std::max<uint64_t>(1, element.fixed_bytes()));
        cursor.skip(bytes);
        continue;
      }
      for (uint64_t instance = 0; instance < element.count; ++instance) {
        for (const PlyProperty& p : element.properties) {
          if (!p.is_list) {
            if (cursor.left() < p.value.bytes) return truncated(element, instance);
            cursor.skip(p.value.bytes);
            continue;
          }
          unsigned char raw[8];
          if (!cursor.read(raw, p.count.bytes)) return truncated(element, instance);
          const auto items = decode_count(raw, p.count, big_endian);
          if (!items)
            return fail(fmt::format("element '{}' #{}: a negative list count (corrupt file)", element.name, instance));
          const uint64_t bytes = saturating_mul_add(0, *items, p.value.bytes);
          if (bytes > cursor.left())
            return fail(fmt::format("element '{}' #{}: a list of {} items ({} bytes) cannot fit in the {} bytes "
                                    "left (corrupt count)",
                                    element.name, instance, *items, bytes, cursor.left()));
          cursor.skip(bytes);
        }
      }
    }
    return Status::success();
  }

  // One instance per non-blank line, as assimp 5.2 reads ascii bodies (it skips blank lines). A body
  // with fewer lines than the header declares is refused: assimp 5.2 reads on past the end of a short
  // ascii body (found by fuzz_scene_loader: 21 GB from a 2.4 KB file). A line must hold a word for
  // each scalar property, list counts must be plain integers that fit in its remaining words; other
  // oddities are left to assimp's own errors.
  Status walk_ascii() {
    std::ifstream in(file_, std::ios::binary);
    if (!in) return make_error(ErrorCode::io_error, fmt::format("{}: cannot open", file_.string()));
    in.seekg(std::streamoff(header_.body_offset));
    std::string line;
    std::vector<std::string_view> words;
    uint64_t line_number = 0;
    bool nul_byte = false;
    const char* line_break = nullptr;
    auto next_data_line = [&] {
      while (std::getline(in, line)) {
        ++line_number;
        // assimp 5.2 reads an ascii body as a C string: a NUL byte ends it there, and a body that
        // ends early is read on past its end (found by fuzz_scene_loader: a 2 GB allocation).
        if (line.find('\0') != std::string::npos) return !(nul_byte = true);
        if ((line_break = strip_line_end(line))) return false;
        split_words(line, words);
        if (!words.empty()) return true;
      }
      return false;
    };
    for (const PlyElement& element : header_.elements) {
      for (uint64_t instance = 0; instance < element.count; ++instance) {
        if (!next_data_line()) {
          if (nul_byte)
            return fail(fmt::format("a NUL byte in the ascii body (line {}), which ends it for the importer",
                                    line_number));
          if (line_break) return fail(fmt::format("{} in the ascii body (line {})", line_break, line_number));
          return fail(fmt::format("the body ends at element '{}' #{} of {} (truncated file)", element.name, instance,
                                  element.count));
        }
        size_t word = 0;
        for (const PlyProperty& p : element.properties) {
          // assimp 5.2 reads a scalar missing from its line past the line's end (found by
          // fuzz_scene_loader: a 3-float vertex line of 2 words made it allocate 16 GB): every
          // scalar property needs its word. A list missing at the end of a line reads as empty
          // (assimp's own test model PLY/issue623.ply has one per vertex).
          if (word >= words.size()) {
            if (p.is_list) break;
            return fail(fmt::format("element '{}' #{} (body line {}): {} words for {} properties (a short line)",
                                    element.name, instance, line_number, words.size(), element.properties.size()));
          }
          if (!p.is_list) {
            ++word;
            continue;
          }
          uint64_t items = 0;
          // assimp 5.2 reads a count's leading digits and ignores the rest, so "123333333330.000"
          // became a list of 10^11 items (found by fuzz_scene_loader: 2.2 GB from a 4 KB file).
          if (!parse_count(words[word], &items))
            return fail(fmt::format("element '{}' #{} (body line {}): list count '{}' is not a plain integer",
                                    element.name, instance, line_number, words[word]));
          ++word;
          if (items > words.size() - word)
            return fail(fmt::format("element '{}' #{} (body line {}): a list of {} items on a line that holds {} more "
                                    "words (corrupt count)",
                                    element.name, instance, line_number, items, words.size() - word));
          word += size_t(items);
        }
      }
    }
    return Status::success();
  }

  const std::filesystem::path& file_;
  const uint64_t file_size_;
  PlyHeader header_;
};

}  // namespace

Status check_ply_file(const std::filesystem::path& file, uint64_t file_size) {
  return PlyChecker(file, file_size).run();
}

Status check_off_file(const std::filesystem::path& file, uint64_t file_size) {
  const std::string head = read_head(file, 1 << 16);
  std::vector<std::string_view> counts;
  size_t pos = 0;
  bool keyword_seen = false;
  while (pos < head.size() && counts.size() < 2) {
    size_t end = head.find('\n', pos);
    if (end == std::string::npos) end = head.size();
    std::string line(head, pos, end - pos);
    if (const char* problem = strip_line_end(line))  // assimp would split the line there too
      return make_error(ErrorCode::invalid_input, fmt::format("{}: OFF: {} in the header", file.string(), problem));
    // Words of `head`, not of `line`: `counts` keeps them past this line.
    auto words = split_words(std::string_view(head).substr(pos, line.size()));
    pos = end + 1;
    if (words.empty() || words[0][0] == '#') continue;
    size_t first = 0;
    if (!keyword_seen && words[0].find("OFF") != std::string_view::npos) {
      // OFF, COFF, NOFF, STOFF, 4OFF, nOFF...: a keyword with anything glued after it ("OFF#81",
      // found by fuzz_scene_loader) is read by assimp 5.2 from other positions than ours, and made it
      // read out of bounds (SEGV). The keyword must end the word.
      const std::string_view keyword = words[0];
      if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF" ||
          keyword.find_first_not_of("STCN4n") < keyword.size() - 3)
        return make_error(ErrorCode::invalid_input, fmt::format("{}: OFF: unknown header keyword '{}'", file.string(),
                                                                keyword.substr(0, 32)));
      first = 1;
    }
    // The format allows a body without its keyword line, but assimp 5.2 then reads the counts and lines
    // otherwise than the format says: it dropped faces, kept the mesh's face count and read out of
    // bounds (SEGV, found by fuzz_scene_loader). Every OFF file we know of (assimp's test models,
    // ModelNet, Princeton's benchmark) starts with the keyword, so a file without it is refused.
    if (!keyword_seen && first == 0)
      return make_error(ErrorCode::invalid_input,
                        fmt::format("{}: OFF: the file must start with its keyword line (OFF, COFF, NOFF, STOFF, "
                                    "4OFF or nOFF), found '{}'",
                                    file.string(), words[0].substr(0, 32)));
    keyword_seen = true;
    for (size_t w = first; w < words.size() && counts.size() < 2; ++w) counts.push_back(words[w]);
  }
  auto fail = [&](const std::string& why) {
    return make_error(ErrorCode::invalid_input, fmt::format("{}: OFF: {}", file.string(), why));
  };
  // assimp 5.2 reads the counts as the first two numbers wherever they are, as 32-bit values that
  // wrap, and a float's integer part ("60.000" -> 60): a vertex count of 6666666666653 followed by a
  // vertex line allocated 10.5 GB (found by fuzz_scene_loader). Both counts must be plain integers.
  uint64_t vertices = 0, faces = 0;
  if (counts.size() < 2 || !parse_count(counts[0], &vertices) || !parse_count(counts[1], &faces))
    return fail(fmt::format("the header must give the vertex and face counts as integers (found '{}')",
                            counts.empty() ? std::string_view() : counts.back().substr(0, 32)));
  // A vertex takes at least "0 0 0\n", a face at least "0\n".
  if (saturating_mul_add(saturating_mul_add(0, vertices, 6), faces, 2) > file_size)
    return fail(fmt::format("{} vertices and {} faces cannot fit in {} bytes (corrupt counts)", vertices, faces,
                            file_size));
  // The body, as assimp 5.2 reads it: data lines are the non-blank lines, vertices first, then one
  // face per line ("n i1 ... in", colour values may follow). assimp reads a face's indices without
  // checking them against the vertex count (found by fuzz_scene_loader: out-of-bounds reads, a
  // crash), so every index must name a vertex and a face must hold as many indices as it says.
  std::ifstream in(file, std::ios::binary);
  if (!in) return make_error(ErrorCode::io_error, fmt::format("{}: cannot open", file.string()));
  in.seekg(std::streamoff(std::min(pos, head.size())));
  std::string line;
  std::string refused;  // why the body's reading stopped early, when it is refused for it
  auto next_data_line = [&](std::vector<std::string_view>* words) {
    while (std::getline(in, line)) {
      // As for PLY: assimp 5.2 reads the text as a C string, so a NUL byte ends the file there.
      if (line.find('\0') != std::string::npos) {
        refused = "a NUL byte in the body, which ends it for the importer";
        return false;
      }
      if (const char* line_break = strip_line_end(line)) {
        refused = std::string(line_break) + " in the body";
        return false;
      }
      split_words(line, *words);
      if (!words->empty()) return true;
    }
    return false;
  };
  // Refused, or else short (assimp reports that).
  const auto stopped = [&] { return refused.empty() ? Status::success() : Status(fail(refused)); };
  std::vector<std::string_view> words;
  for (uint64_t v = 0; v < vertices; ++v)
    if (!next_data_line(&words)) return stopped();
  for (uint64_t f = 0; f < faces; ++f) {
    if (!next_data_line(&words)) return stopped();
    uint64_t n = 0;
    if (!parse_count(words[0], &n))
      return fail(fmt::format("face #{} does not start with its vertex count ('{}')", f, words[0].substr(0, 32)));
    // assimp 5.2 drops a face of no vertex and keeps a mesh with fewer faces than it allocated, which
    // crashed it (SEGV inside ReadFile, found by fuzz_scene_loader: "OFF\n81 1 0" whose one face is "0 ...").
    if (n == 0) return fail(fmt::format("face #{} has no vertices", f));
    if (n > words.size() - 1)
      return fail(fmt::format("face #{} declares {} vertices and lists {}", f, n, words.size() - 1));
    for (uint64_t i = 1; i <= n; ++i) {
      uint64_t index = 0;
      if (!parse_count(words[i], &index))
        return fail(fmt::format("face #{}: '{}' is not a vertex index", f, words[i].substr(0, 32)));
      if (index >= vertices)
        return fail(fmt::format("face #{}: vertex index {} is out of range (the file has {} vertices)", f, index,
                                vertices));
    }
  }
  return Status::success();
}

}  // namespace shadowtiles
