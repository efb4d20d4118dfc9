#include "visproxy/mesh/write_mesh.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "visproxy/mesh/read_mesh.h"

namespace visproxy {
namespace {

template <typename T>
void append_little_endian(std::string& out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

void append_decimal(std::string& out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);  // shortest round-trip form
  out.append(buffer, result.ptr);
}

void append_decimal(std::string& out, std::uint64_t value) {
  char buffer[24];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

}  // namespace

std::string encode_ply(const TriangleMesh& mesh) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\ncomment visproxy\nelement vertex " + std::to_string(mesh.positions.size()) +
      "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
      std::to_string(mesh.triangles.size()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  out.reserve(out.size() + mesh.positions.size() * 24 + mesh.triangles.size() * 13);
  for (const Vertex& p : mesh.positions)
    for (int axis = 0; axis < 3; ++axis) append_little_endian(out, p[axis]);
  for (const Triangle& triangle : mesh.triangles) {
    out.push_back(3);
    for (const VertexIndex index : triangle) append_little_endian(out, index);
  }
  return out;
}

std::string encode_obj(const TriangleMesh& mesh) {
  std::string out = "# visproxy\n";
  out.reserve(mesh.positions.size() * 40 + mesh.triangles.size() * 24);
  for (const Vertex& p : mesh.positions) {
    out += "v";
    for (int axis = 0; axis < 3; ++axis) {
      out += ' ';
      append_decimal(out, p[axis]);
    }
    out += '\n';
  }
  for (const Triangle& triangle : mesh.triangles) {
    out += "f";
    for (const VertexIndex index : triangle) {
      out += ' ';
      append_decimal(out, std::uint64_t{index} + 1);
    }
    out += '\n';
  }
  return out;
}

void write_mesh(const std::filesystem::path& path, const TriangleMesh& mesh) {
  const std::optional<MeshFormat> format = format_from_extension(path);
  if (format == MeshFormat::ply) return write_file_atomically(path, encode_ply(mesh));
  if (format == MeshFormat::obj) return write_file_atomically(path, encode_obj(mesh));
  throw InvalidInputError(path, "meshes are written as .ply or .obj only");
}

}  // namespace visproxy
