// Polygon File Format (Stanford PLY): ascii, binary_little_endian, binary_big_endian.
// Only the `vertex` element's x, y, z and the `face` element's index list are used;
// every other element and property is read past, and header lines that start with no PLY
// keyword are skipped with a warning.

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy::parsing {
namespace {

enum class Scalar { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

bool scalar_from_name(std::string_view name, Scalar& type) {
  static constexpr std::pair<std::string_view, Scalar> kNames[] = {
      {"char", Scalar::int8},     {"int8", Scalar::int8},       {"uchar", Scalar::uint8},
      {"uint8", Scalar::uint8},   {"short", Scalar::int16},     {"int16", Scalar::int16},
      {"ushort", Scalar::uint16}, {"uint16", Scalar::uint16},   {"int", Scalar::int32},
      {"int32", Scalar::int32},   {"uint", Scalar::uint32},     {"uint32", Scalar::uint32},
      {"float", Scalar::float32}, {"float32", Scalar::float32}, {"double", Scalar::float64},
      {"float64", Scalar::float64}};
  for (const auto& [text, value] : kNames)
    if (text == name) {
      type = value;
      return true;
    }
  return false;
}

std::size_t scalar_size(Scalar type) {
  switch (type) {
    case Scalar::int8:
    case Scalar::uint8: return 1;
    case Scalar::int16:
    case Scalar::uint16: return 2;
    case Scalar::int32:
    case Scalar::uint32:
    case Scalar::float32: return 4;
    case Scalar::float64: return 8;
  }
  return 0;
}

struct Property {
  std::string name;
  Scalar type = Scalar::float32;
  bool is_list = false;
  Scalar count_type = Scalar::uint8;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Encoding { ascii, little_endian, big_endian };

// Bounds-checked reads from the binary body.
class BinaryReader {
 public:
  BinaryReader(std::string_view bytes, std::size_t start, bool swap, const std::filesystem::path& source)
      : bytes_(bytes), position_(start), swap_(swap), source_(source) {}

  double read(Scalar type, std::string_view what) {
    const std::size_t size = scalar_size(type);
    if (bytes_.size() - position_ < size)
      throw InvalidInputError(source_, "truncated: the file ends inside " + std::string(what) + " (byte " +
                                           std::to_string(position_) + ")");
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + position_, size);
    position_ += size;
    if (swap_) std::reverse(raw, raw + size);
    switch (type) {
      case Scalar::int8: return static_cast<std::int8_t>(raw[0]);
      case Scalar::uint8: return raw[0];
      case Scalar::int16: return load<std::int16_t>(raw);
      case Scalar::uint16: return load<std::uint16_t>(raw);
      case Scalar::int32: return load<std::int32_t>(raw);
      case Scalar::uint32: return load<std::uint32_t>(raw);
      case Scalar::float32: return load<float>(raw);
      case Scalar::float64: return load<double>(raw);
    }
    return 0;
  }
  std::size_t bytes_left() const { return bytes_.size() - position_; }

 private:
  template <typename T>
  static double load(const unsigned char* raw) {
    T value;
    std::memcpy(&value, raw, sizeof value);
    return static_cast<double>(value);
  }

  std::string_view bytes_;
  std::size_t position_;
  bool swap_;
  const std::filesystem::path& source_;
};

// Reads one scalar, whatever the encoding.
class BodyReader {
 public:
  BodyReader(std::string_view bytes, std::size_t start, Encoding encoding, const std::filesystem::path& source)
      : encoding_(encoding),
        text_(bytes, source),
        binary_(bytes, start, (encoding == Encoding::big_endian) == (std::endian::native == std::endian::little), source),
        source_(source) {
    text_.seek(start);
  }

  double number(Scalar type, std::string_view what) {
    if (encoding_ != Encoding::ascii) return binary_.read(type, what);
    return text_.read_number(what);
  }

  // A list length or an index: a whole number in [0, limit).
  std::uint64_t index(Scalar type, std::string_view what, std::uint64_t limit) {
    const double value = encoding_ == Encoding::ascii ? text_.read_number(what) : binary_.read(type, what);
    if (!(value >= 0) || value != std::floor(value) || value >= static_cast<double>(limit)) {
      char shown[32];
      std::snprintf(shown, sizeof shown, "%.17g", value);
      fail(std::string(what) + " " + std::string(shown) + " is out of range (" + std::to_string(limit) + " allowed)");
    }
    return static_cast<std::uint64_t>(value);
  }

  std::size_t bytes_left() const { return encoding_ == Encoding::ascii ? text_.bytes_left() : binary_.bytes_left(); }

  [[noreturn]] void fail(std::string_view problem) const {
    if (encoding_ == Encoding::ascii) text_.fail(problem);
    throw InvalidInputError(source_, problem);
  }

 private:
  Encoding encoding_;
  TextScanner text_;
  BinaryReader binary_;
  const std::filesystem::path& source_;
};

}  // namespace

TriangleMesh parse_ply(std::string_view bytes, const std::filesystem::path& source, const WarningHandler& on_warning) {
  TextScanner header(bytes, source);
  if (header.token_on_line() != "ply") header.fail("does not start with 'ply'");
  header.skip_line();

  Encoding encoding = Encoding::ascii;
  bool have_format = false;
  std::vector<Element> elements;
  // Lines that start with no PLY keyword, such as Blender 2.4x's "Created by Blender3D 247 -
  // www.blender.org, source file: ..." after `format`: skipped, as rply and Assimp do, and
  // reported once the header is known to end (a file that is no PLY at all gets one error).
  std::vector<std::string> warnings;
  std::uint64_t unreported_lines = 0;
  constexpr std::size_t kMaxWarnings = 8;
  for (;;) {
    if (!header.skip_to_token()) header.fail("the header has no 'end_header' line");
    const std::size_t line_start = header.position();
    const std::string_view keyword = header.token_on_line();
    if (keyword == "end_header") {
      header.skip_line();
      break;
    }
    if (keyword == "comment" || keyword == "obj_info") {
    } else if (keyword == "format") {
      const std::string_view name = header.token_on_line();
      if (name == "ascii") encoding = Encoding::ascii;
      else if (name == "binary_little_endian") encoding = Encoding::little_endian;
      else if (name == "binary_big_endian") encoding = Encoding::big_endian;
      else header.fail("unknown PLY format " + quote_token(name));
      if (header.token_on_line() != "1.0") header.fail("unsupported PLY version (only 1.0)");
      have_format = true;
    } else if (keyword == "element") {
      Element element;
      element.name = header.token_on_line();
      if (element.name.empty()) header.fail("element without a name");
      element.count = header.read_count("the element count", true);
      elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (elements.empty()) header.fail("property before any element");
      Property property;
      std::string_view type = header.token_on_line();
      if (type == "list") {
        property.is_list = true;
        if (!scalar_from_name(header.token_on_line(), property.count_type)) header.fail("unknown list count type");
        type = header.token_on_line();
      }
      if (!scalar_from_name(type, property.type)) header.fail("unknown property type " + quote_token(type));
      property.name = header.token_on_line();
      if (property.name.empty()) header.fail("property without a name");
      elements.back().properties.push_back(std::move(property));
    } else if (warnings.size() < kMaxWarnings) {
      std::string_view text = bytes.substr(line_start, bytes.find('\n', line_start) - line_start);
      while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
      warnings.push_back(
          located_message(source, "unknown header line " + quote_token(text, 120) + " ignored", header.line()));
    } else {
      ++unreported_lines;
    }
    header.skip_line();
  }
  if (on_warning) {
    for (const std::string& warning : warnings) on_warning(warning);
    if (unreported_lines > 0)
      on_warning(located_message(source, std::to_string(unreported_lines) + " more unknown header lines ignored"));
  }
  if (!have_format) header.fail("the header has no 'format' line");

  const Element* vertex_element = nullptr;
  const Element* face_element = nullptr;
  for (const Element& element : elements) {
    if (element.name == "vertex") vertex_element = &element;
    if (element.name == "face") face_element = &element;
  }
  if (vertex_element == nullptr) header.fail("the header declares no 'vertex' element");
  if (face_element == nullptr || face_element->count == 0) throw InvalidInputError(source, "contains no faces");

  static constexpr const char* kAxisNames[3] = {"x", "y", "z"};
  int coordinate_property[3] = {-1, -1, -1};
  for (std::size_t p = 0; p < vertex_element->properties.size(); ++p) {
    const Property& property = vertex_element->properties[p];
    for (int axis = 0; axis < 3; ++axis)
      if (property.name == kAxisNames[axis] && !property.is_list) coordinate_property[axis] = static_cast<int>(p);
  }
  for (int axis = 0; axis < 3; ++axis)
    if (coordinate_property[axis] < 0)
      header.fail(std::string("the vertex element has no scalar '") + kAxisNames[axis] + "' property");
  int index_property = -1;
  for (std::size_t p = 0; p < face_element->properties.size(); ++p) {
    const Property& property = face_element->properties[p];
    if (property.is_list && (property.name == "vertex_indices" || property.name == "vertex_index"))
      index_property = static_cast<int>(p);
  }
  if (index_property < 0) header.fail("the face element has no 'vertex_indices' list");

  // Every declared element must fit in what follows the header before anything is allocated.
  const std::size_t body_start = header.position();
  const std::size_t body_size = bytes.size() - body_start;
  std::uint64_t smallest_body = 0;
  for (const Element& element : elements) {
    std::uint64_t smallest_item = 0;
    for (const Property& property : element.properties)
      smallest_item += encoding == Encoding::ascii ? 2 : scalar_size(property.is_list ? property.count_type : property.type);
    if (smallest_item > 0 && element.count > (body_size - std::min<std::uint64_t>(smallest_body, body_size)) / smallest_item)
      throw InvalidInputError(source, "header claims " + std::to_string(element.count) + " " + quote_token(element.name) +
                                          " elements, more than the " + std::to_string(body_size) +
                                          " bytes after the header can hold");
    smallest_body += element.count * smallest_item;
  }

  BodyReader body(bytes, body_start, encoding, source);
  MeshBuilder builder(source);
  builder.reserve(vertex_element->count, face_element->count);
  std::vector<std::uint64_t> corners;
  double values[3] = {0, 0, 0};
  for (const Element& element : elements) {
    if (element.properties.empty()) continue;
    const bool is_vertex = &element == vertex_element;
    const bool is_face = &element == face_element;
    for (std::uint64_t item = 0; item < element.count; ++item) {
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const Property& property = element.properties[p];
        if (property.is_list) {
          const std::uint64_t length = body.index(property.count_type, "a list length", body.bytes_left() + 1);
          const bool wanted = is_face && static_cast<int>(p) == index_property;
          if (wanted) {
            if (length < 3) body.fail("face " + std::to_string(item) + " has " + std::to_string(length) + " corners; a face needs 3 or more");
            corners.resize(length);
            for (std::uint64_t& corner : corners) corner = body.index(property.type, "a vertex index", vertex_element->count);
            builder.add_polygon(corners);
          } else {
            for (std::uint64_t k = 0; k < length; ++k) body.number(property.type, "a list entry");
          }
        } else {
          const double value = body.number(property.type, property.name.empty() ? "a property" : property.name);
          if (is_vertex) {
            for (int axis = 0; axis < 3; ++axis)
              if (static_cast<int>(p) == coordinate_property[axis]) {
                if (!std::isfinite(value)) body.fail("vertex " + std::to_string(item) + " has a non-finite coordinate");
                values[axis] = value;
              }
          }
        }
      }
      if (is_vertex) builder.add_vertex(values[0], values[1], values[2]);
    }
  }
  return builder.finish();
}

}  // namespace visproxy::parsing
