#include "mesh/encode_formats.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace visproxy::testing {
namespace {

template <typename T>
void append(std::string& out, T value, bool big_endian) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

void append_scalar(std::string& out, const std::string& type, double value, bool big_endian) {
  if (type == "char" || type == "int8") append(out, static_cast<std::int8_t>(value), big_endian);
  else if (type == "uchar" || type == "uint8") append(out, static_cast<std::uint8_t>(value), big_endian);
  else if (type == "short" || type == "int16") append(out, static_cast<std::int16_t>(value), big_endian);
  else if (type == "ushort" || type == "uint16") append(out, static_cast<std::uint16_t>(value), big_endian);
  else if (type == "int" || type == "int32") append(out, static_cast<std::int32_t>(value), big_endian);
  else if (type == "uint" || type == "uint32") append(out, static_cast<std::uint32_t>(value), big_endian);
  else if (type == "float" || type == "float32") append(out, static_cast<float>(value), big_endian);
  else if (type == "double" || type == "float64") append(out, value, big_endian);
  else throw std::invalid_argument("unknown PLY type " + type);
}

std::string text(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

}  // namespace

std::string encode_ply_variant(const TriangleMesh& mesh, const PlyLayout& layout) {
  const char* format = layout.encoding == PlyEncoding::ascii           ? "ascii"
                       : layout.encoding == PlyEncoding::little_endian ? "binary_little_endian"
                                                                       : "binary_big_endian";
  std::string out = "ply\nformat " + std::string(format) + " 1.0\ncomment test\n";
  out += "element vertex " + std::to_string(mesh.positions.size()) + "\n";
  if (layout.extra_properties) out += "property float nx\n";
  out += "property " + layout.coordinate_type + " x\nproperty " + layout.coordinate_type + " y\nproperty " +
         layout.coordinate_type + " z\n";
  if (layout.extra_properties) out += "property uchar red\n";
  if (layout.extra_properties) out += "element material 1\nproperty list uchar float values\n";
  out += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  if (layout.extra_properties) out += "property int flags\n";
  out += "property list " + layout.count_type + " " + layout.index_type + " vertex_indices\n";
  if (layout.extra_properties) out += "property list uchar float texcoord\n";
  out += "end_header\n";

  const bool ascii = layout.encoding == PlyEncoding::ascii;
  const bool big = layout.encoding == PlyEncoding::big_endian;
  auto put = [&](const std::string& type, double value) {
    if (ascii) out += text(value) + " ";
    else append_scalar(out, type, value, big);
  };
  auto end_item = [&] {
    if (ascii) out += "\n";
  };
  for (const Vertex& p : mesh.positions) {
    if (layout.extra_properties) put("float", 0.5);
    for (int axis = 0; axis < 3; ++axis) put(layout.coordinate_type, p[axis]);
    if (layout.extra_properties) put("uchar", 200);
    end_item();
  }
  if (layout.extra_properties) {
    put("uchar", 2);
    put("float", 1.5);
    put("float", -2.5);
    end_item();
  }
  for (const Triangle& t : mesh.triangles) {
    if (layout.extra_properties) put("int", -7);
    put(layout.count_type, 3);
    for (const VertexIndex index : t) put(layout.index_type, index);
    if (layout.extra_properties) {
      put("uchar", 2);
      put("float", 0.25);
      put("float", 0.75);
    }
    end_item();
  }
  return out;
}

std::string encode_off(const TriangleMesh& mesh) {
  std::string out = "OFF\n# a comment\n" + std::to_string(mesh.positions.size()) + " " +
                    std::to_string(mesh.triangles.size()) + " 0\n";
  for (const Vertex& p : mesh.positions) out += text(p.x()) + " " + text(p.y()) + " " + text(p.z()) + "\n";
  for (const Triangle& t : mesh.triangles)
    out += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  return out;
}

std::string encode_ascii_stl(const TriangleMesh& mesh) {
  std::string out = "solid test object\n";
  for (const Triangle& t : mesh.triangles) {
    out += "  facet normal 0 0 1\n    outer loop\n";
    for (const VertexIndex index : t) {
      const Vertex& p = mesh.positions[index];
      out += "      vertex " + text(p.x()) + " " + text(p.y()) + " " + text(p.z()) + "\n";
    }
    out += "    endloop\n  endfacet\n";
  }
  return out + "endsolid test object\n";
}

std::string encode_binary_stl(const TriangleMesh& mesh, const std::string& header) {
  std::string out = header.substr(0, 80);
  out.resize(80, ' ');
  append(out, static_cast<std::uint32_t>(mesh.triangles.size()), false);
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) append(out, 0.0f, false);
    for (const VertexIndex index : t)
      for (int axis = 0; axis < 3; ++axis) append(out, static_cast<float>(mesh.positions[index][axis]), false);
    append(out, std::uint16_t{0}, false);
  }
  return out;
}

}  // namespace visproxy::testing
