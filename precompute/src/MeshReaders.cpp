// MeshReaders.cpp — the OFF and PLY readers brittle parses itself (MeshReaders.h); no CGAL here.
#include "MeshReaders.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace brittle::detail {

namespace {

// The whole mesh file as text. Error: FileNotFound.
Result<std::string> readMeshText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in && !in.eof()) return makeError(ErrorCode::FileNotFound, "cannot read mesh file " + path.string());
  return text;
}

// ----- OFF, read by brittle itself -----------------------------------------------------------
// CGAL 5.5's OFF scanner is not safe on bad input (found by tests/fuzz): it reads past the end of
// a vector on a COFF colour line, casts out-of-range face indices from double to size_t, and
// sizes its arrays from the header's counts before it reads a vertex, so a 20-byte file can ask
// for gigabytes. This reader keeps to what the files in use hold: the text format, one vertex or
// face per line, "#" comments anywhere.

// The non-empty lines of a file, split into tokens, comments removed.
struct OffLine {
  size_t number;  // 1-based
  std::vector<std::string_view> tokens;
};

std::vector<OffLine> splitOffLines(std::string_view text) {
  std::vector<OffLine> lines;
  size_t number = 0;
  for (size_t start = 0; start < text.size();) {
    const size_t end = std::min(text.find('\n', start), text.size());
    ++number;
    std::string_view line = text.substr(start, end - start);
    line = line.substr(0, line.find('#'));
    OffLine parsed{number, {}};
    for (size_t i = 0; i < line.size();) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      const size_t first = i;
      while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      if (i > first) parsed.tokens.push_back(line.substr(first, i - first));
    }
    if (!parsed.tokens.empty()) lines.push_back(std::move(parsed));
    start = end + 1;
  }
  return lines;
}

// The whole token as a number, or nothing. A leading '+' is allowed, as stream extraction allows it.
template <typename T>
std::optional<T> parseWhole(std::string_view token) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  T value{};
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

}  // namespace

Result<PolygonSoup> readOff(const std::filesystem::path& path) {
  const std::string file = path.filename().string();
  auto read = readMeshText(path);
  if (!read) return read.error();
  const std::string& text = read.value();
  const std::vector<OffLine> lines = splitOffLines(text);
  auto bad = [&](size_t line, const std::string& what) {
    return makeError(ErrorCode::ParseError, file + " line " + std::to_string(line) + ": " + what);
  };
  if (lines.empty()) return makeError(ErrorCode::ParseError, file + ": no OFF header");

  // [ST][C][N][4]OFF: textures, colours and normals follow the coordinates and are ignored; 4OFF
  // gives homogeneous coordinates.
  std::string_view keyword = lines[0].tokens[0];
  for (std::string_view prefix : {"ST", "C", "N"}) {
    if (keyword.starts_with(prefix)) keyword.remove_prefix(prefix.size());
  }
  const bool homogeneous = keyword.starts_with("4");
  if (homogeneous) keyword.remove_prefix(1);
  if (keyword != "OFF") {
    return bad(lines[0].number, "'" + std::string(lines[0].tokens[0]) +
                                    "' is not an OFF header (read: OFF, COFF, NOFF, STOFF, 4OFF and their combinations)");
  }
  // The counts follow the keyword on its line or on the next.
  size_t next = 1;
  std::vector<std::string_view> counts(lines[0].tokens.begin() + 1, lines[0].tokens.end());
  if (!counts.empty() && counts[0] == "BINARY") return bad(lines[0].number, "binary OFF is not supported");
  if (counts.empty() && next < lines.size()) counts = lines[next++].tokens;
  const size_t countsLine = lines[next - 1].number;
  const auto vertexCount = counts.size() >= 2 ? parseWhole<uint64_t>(counts[0]) : std::nullopt;
  const auto faceCount = counts.size() >= 2 ? parseWhole<uint64_t>(counts[1]) : std::nullopt;
  if (!vertexCount || !faceCount) return bad(countsLine, "expected the vertex and face counts");
  // One line per vertex and per face: a count beyond the lines left is a lie, refused before
  // anything is allocated for it.
  const size_t linesLeft = lines.size() - next;
  if (*vertexCount > linesLeft || *faceCount > linesLeft - *vertexCount) {
    return bad(countsLine, "declares " + std::to_string(*vertexCount) + " vertices and " +
                               std::to_string(*faceCount) + " faces, but only " + std::to_string(linesLeft) +
                               " lines follow");
  }

  PolygonSoup soup;
  const size_t dims = homogeneous ? 4 : 3;
  soup.points.reserve(*vertexCount);
  for (uint64_t v = 0; v < *vertexCount; ++v) {
    const OffLine& line = lines[next++];
    if (line.tokens.size() < dims) return bad(line.number, "a vertex needs " + std::to_string(dims) + " coordinates");
    std::array<double, 4> x = {0.0, 0.0, 0.0, 1.0};
    for (size_t d = 0; d < dims; ++d) {
      const auto value = parseWhole<double>(line.tokens[d]);
      if (!value) return bad(line.number, "'" + std::string(line.tokens[d]) + "' is not a number");
      x[d] = *value;
    }
    for (double& c : x) c /= x[3];
    if (!std::all_of(x.begin(), x.end(), [](double c) { return std::isfinite(c); })) {
      return makeError(ErrorCode::NonFiniteValue,
                       "non-finite coordinate in " + file + " at line " + std::to_string(line.number));
    }
    soup.points.push_back({x[0], x[1], x[2]});
  }
  soup.polygons.reserve(*faceCount);
  for (uint64_t f = 0; f < *faceCount; ++f) {
    const OffLine& line = lines[next++];
    const auto corners = parseWhole<uint64_t>(line.tokens[0]);
    if (!corners || *corners + 1 > line.tokens.size()) {
      return bad(line.number, "a face is its corner count followed by that many vertex indices");
    }
    std::vector<std::size_t>& polygon = soup.polygons.emplace_back();
    for (uint64_t k = 1; k <= *corners; ++k) {
      const auto index = parseWhole<uint64_t>(line.tokens[k]);
      if (!index) return bad(line.number, "'" + std::string(line.tokens[k]) + "' is not a vertex index");
      if (*index >= *vertexCount) {
        return bad(line.number, "face " + std::to_string(f) + " refers to vertex " + std::to_string(*index) + " of " +
                                    std::to_string(*vertexCount));
      }
      polygon.push_back(static_cast<std::size_t>(*index));
    }
  }
  return soup;
}

namespace {

// ----- PLY, read by brittle itself ----------------------------------------------------------
// CGAL 5.5's PLY reader is not safe on bad input either: a "property" line before any "element"
// line makes it write through back() of an empty vector (found by tests/fuzz), an element of 2^64
// items without properties makes it loop, pushing a point per item, without reading a byte, and a
// list length sizes a buffer before the list is read.
// This reader reads every format (ascii, binary little and big endian), takes x, y, z from the
// "vertex" element and "vertex_indices" (or "vertex_index") from the "face" element, and skips
// every other element and property. Nothing is sized from a count before the data that the count
// promises has been seen to fit in the file.

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };
enum class PlyType { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

std::optional<PlyType> plyType(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, PlyType>, 16> kNames = {{
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},       {"uchar", PlyType::Uint8},
      {"uint8", PlyType::Uint8},   {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::Uint16}, {"uint16", PlyType::Uint16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},   {"uint", PlyType::Uint32},     {"uint32", PlyType::Uint32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64},
  }};
  for (const auto& [n, type] : kNames) {
    if (n == name) return type;
  }
  return std::nullopt;
}

size_t plySize(PlyType type) {
  switch (type) {
    case PlyType::Int8:
    case PlyType::Uint8: return 1;
    case PlyType::Int16:
    case PlyType::Uint16: return 2;
    case PlyType::Int32:
    case PlyType::Uint32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 8;
}

bool plyIsInteger(PlyType type) { return type != PlyType::Float32 && type != PlyType::Float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;  // of the items, for a list
  bool isList = false;
  PlyType countType = PlyType::Uint8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

// Reads the values of the body one at a time, as doubles (exact for every PLY type).
class PlyBody {
 public:
  PlyBody(std::string_view bytes, PlyFormat format) : mBytes(bytes), mFormat(format) {}

  /// False at the end of the data or on a token that is not a value of the type.
  bool read(PlyType type, double& value) {
    if (mFormat == PlyFormat::Ascii) return readToken(type, value);
    const size_t size = plySize(type);
    if (mBytes.size() - mAt < size) return false;
    std::array<unsigned char, 8> raw{};
    std::memcpy(raw.data(), mBytes.data() + mAt, size);
    mAt += size;
    if ((mFormat == PlyFormat::BinaryBigEndian) == (std::endian::native == std::endian::little)) {
      std::reverse(raw.begin(), raw.begin() + static_cast<std::ptrdiff_t>(size));
    }
    value = decode(type, raw.data());
    return true;
  }

  /// Whether `items` more values of at least `bytesEach` bytes (binary) or one character (ascii)
  /// each can still be in the data: a bound on a count before anything is read for it.
  bool canHold(uint64_t items, size_t bytesEach) const {
    const size_t left = mBytes.size() - mAt;
    return mFormat == PlyFormat::Ascii ? items <= left : items <= left / std::max<size_t>(bytesEach, 1);
  }

 private:
  static double decode(PlyType type, const unsigned char* raw) {
    auto as = [raw]<typename T>(T) {
      T v;
      std::memcpy(&v, raw, sizeof v);
      return static_cast<double>(v);
    };
    switch (type) {
      case PlyType::Int8: return as(int8_t{});
      case PlyType::Uint8: return as(uint8_t{});
      case PlyType::Int16: return as(int16_t{});
      case PlyType::Uint16: return as(uint16_t{});
      case PlyType::Int32: return as(int32_t{});
      case PlyType::Uint32: return as(uint32_t{});
      case PlyType::Float32: return as(float{});
      case PlyType::Float64: return as(double{});
    }
    return 0.0;
  }

  static std::pair<int64_t, int64_t> integerRange(PlyType type) {
    switch (type) {
      case PlyType::Int8: return {INT8_MIN, INT8_MAX};
      case PlyType::Uint8: return {0, UINT8_MAX};
      case PlyType::Int16: return {INT16_MIN, INT16_MAX};
      case PlyType::Uint16: return {0, UINT16_MAX};
      case PlyType::Int32: return {INT32_MIN, INT32_MAX};
      case PlyType::Uint32: return {0, UINT32_MAX};
      case PlyType::Float32:
      case PlyType::Float64: break;
    }
    return {0, 0};
  }

  bool readToken(PlyType type, double& value) {
    while (mAt < mBytes.size() && std::isspace(static_cast<unsigned char>(mBytes[mAt]))) ++mAt;
    const size_t first = mAt;
    while (mAt < mBytes.size() && !std::isspace(static_cast<unsigned char>(mBytes[mAt]))) ++mAt;
    const std::string_view token = mBytes.substr(first, mAt - first);
    if (token.empty()) return false;
    if (plyIsInteger(type)) {
      const auto v = parseWhole<int64_t>(token);
      const auto [min, max] = integerRange(type);
      if (!v || *v < min || *v > max) return false;
      value = static_cast<double>(*v);
      return true;
    }
    const auto v = parseWhole<double>(token);
    if (!v) return false;
    value = *v;
    // A float32 property holds what a float can: as CGAL read it, and finite values beyond
    // float's range become infinite instead of undefined.
    if (type == PlyType::Float32) {
      value = std::abs(value) > std::numeric_limits<float>::max() && std::isfinite(value)
                  ? std::copysign(std::numeric_limits<double>::infinity(), value)
                  : static_cast<double>(static_cast<float>(value));
    }
    return true;
  }

  std::string_view mBytes;
  PlyFormat mFormat;
  size_t mAt = 0;
};

}  // namespace

Result<PolygonSoup> readPly(const std::filesystem::path& path) {
  const std::string file = path.filename().string();
  auto read = readMeshText(path);
  if (!read) return read.error();
  const std::string& text = read.value();
  auto bad = [&](const std::string& what) { return makeError(ErrorCode::ParseError, file + ": " + what); };

  // The header: text lines up to "end_header".
  std::optional<PlyFormat> format;
  std::vector<PlyElement> elements;
  size_t at = 0, lineNumber = 0;
  bool ended = false;
  while (!ended && at < text.size()) {
    const size_t end = std::min(text.find('\n', at), text.size());
    std::istringstream line(std::string(text, at, end - at));
    at = end + 1;
    ++lineNumber;
    const std::string where = "header line " + std::to_string(lineNumber) + ": ";
    std::string keyword;
    line >> keyword;
    if (lineNumber == 1) {
      if (keyword != "ply") return bad("not a PLY file (no 'ply' on the first line)");
      continue;
    }
    if (keyword == "format") {
      std::string name;
      line >> name;
      if (name == "ascii") format = PlyFormat::Ascii;
      else if (name == "binary_little_endian") format = PlyFormat::BinaryLittleEndian;
      else if (name == "binary_big_endian") format = PlyFormat::BinaryBigEndian;
      else return bad(where + "unknown format '" + name + "'");
    } else if (keyword == "element") {
      PlyElement element;
      std::string count;
      line >> element.name >> count;
      const auto n = parseWhole<uint64_t>(count);
      if (element.name.empty() || !n) return bad(where + "expected 'element <name> <count>'");
      element.count = *n;
      elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (elements.empty()) return bad(where + "a property before any element");
      PlyProperty property;
      std::string type;
      line >> type;
      property.isList = type == "list";
      std::optional<PlyType> countType = PlyType::Uint8;
      if (property.isList) {
        line >> type;
        countType = plyType(type);
        line >> type;
      }
      const std::optional<PlyType> itemType = plyType(type);
      line >> property.name;
      if (!countType || !itemType || property.name.empty() || (property.isList && !plyIsInteger(*countType))) {
        return bad(where + "expected 'property <type> <name>' or 'property list <integer type> <type> <name>'");
      }
      property.type = *itemType;
      property.countType = *countType;
      elements.back().properties.push_back(std::move(property));
    } else if (keyword == "end_header") {
      ended = true;
    } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
      return bad(where + "unknown keyword '" + keyword + "'");
    }
  }
  if (!ended) return bad("the header has no 'end_header'");
  if (!format) return bad("the header has no 'format' line");

  PlyBody body(std::string_view(text).substr(std::min(at, text.size())), *format);
  PolygonSoup soup;
  for (const PlyElement& element : elements) {
    const bool isVertex = element.name == "vertex" || element.name == "vertices";
    const bool isFace = element.name == "face" || element.name == "faces";
    std::array<int, 3> xyz = {-1, -1, -1};
    int indices = -1;
    for (size_t k = 0; k < element.properties.size(); ++k) {
      const PlyProperty& p = element.properties[k];
      for (int axis = 0; axis < 3; ++axis) {
        if (isVertex && !p.isList && p.name == std::string(1, static_cast<char>('x' + axis))) xyz[axis] = static_cast<int>(k);
      }
      if (isFace && p.isList && plyIsInteger(p.type) && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        indices = static_cast<int>(k);
      }
    }
    if (element.count == 0) continue;
    if (isVertex && std::count(xyz.begin(), xyz.end(), -1) > 0) return bad("the vertex element lacks x, y or z");
    if (isFace && indices < 0) return bad("the face element has no integer list 'vertex_indices'");
    // An element without properties takes no bytes, whatever its count.
    if (element.properties.empty()) continue;
    size_t itemBytes = 0;
    for (const PlyProperty& p : element.properties) itemBytes += plySize(p.isList ? p.countType : p.type);
    if (!body.canHold(element.count, itemBytes)) {
      return bad("element '" + element.name + "' declares " + std::to_string(element.count) +
                 " items, more than the file holds");
    }

    for (uint64_t item = 0; item < element.count; ++item) {
      std::array<double, 3> point = {0.0, 0.0, 0.0};
      for (size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& p = element.properties[k];
        auto badValue = [&](const std::string& what) {
          return bad("element '" + element.name + "' item " + std::to_string(item) + ", property '" + p.name + "': " + what);
        };
        double value = 0.0;
        if (!body.read(p.isList ? p.countType : p.type, value)) return badValue("missing or malformed value");
        if (!p.isList) {
          for (int axis = 0; axis < 3; ++axis) {
            if (xyz[axis] == static_cast<int>(k)) point[axis] = value;
          }
          continue;
        }
        // An integer of at most 32 bits, so exact in a double and in an int64_t.
        const auto length = static_cast<int64_t>(value);
        if (length < 0 || !body.canHold(static_cast<uint64_t>(length), plySize(p.type))) {
          return badValue("list length " + std::to_string(length) + " is negative or more than the file holds");
        }
        std::vector<std::size_t>* polygon = indices == static_cast<int>(k) ? &soup.polygons.emplace_back() : nullptr;
        for (int64_t i = 0; i < length; ++i) {
          if (!body.read(p.type, value)) return badValue("missing or malformed list value");
          if (!polygon) continue;
          if (value < 0.0) return badValue("negative vertex index");
          polygon->push_back(static_cast<std::size_t>(value));
        }
      }
      if (isVertex) soup.points.push_back({point[0], point[1], point[2]});
    }
  }
  return soup;
}

}  // namespace brittle::detail
