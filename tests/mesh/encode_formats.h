#pragma once
// Encoders for the format variants that visproxy reads but does not write, so that the
// readers can be tested on bytes produced from meshes built in code.

#include <string>

#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::testing {

enum class PlyEncoding { ascii, little_endian, big_endian };

struct PlyLayout {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::string coordinate_type = "float";   // any PLY scalar type name
  std::string count_type = "uchar";
  std::string index_type = "int";
  bool extra_properties = false;           // add a normal, a colour and an extra element
};

std::string encode_ply_variant(const TriangleMesh& mesh, const PlyLayout& layout);
std::string encode_off(const TriangleMesh& mesh);
std::string encode_ascii_stl(const TriangleMesh& mesh);
std::string encode_binary_stl(const TriangleMesh& mesh, const std::string& header = std::string(80, ' '));

}  // namespace visproxy::testing
