// Object File Format (Geomview): "OFF" header (optionally prefixed ST, C, N), counts,
// vertex lines, face lines "n i0 ... i(n-1) [colour]". `#` starts a comment.

#include <string>

#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy::parsing {

TriangleMesh parse_off(std::string_view bytes, const std::filesystem::path& source) {
  TextScanner scanner(bytes, source, '#');
  const std::string_view header = scanner.token();
  if (header.size() < 3 || header.substr(header.size() - 3) != "OFF")
    scanner.fail("does not start with an OFF header");
  const std::string_view prefix = header.substr(0, header.size() - 3);
  if (prefix.find_first_not_of("STCN") != std::string_view::npos)
    scanner.fail("unsupported OFF variant " + quote_token(header) + " (only 3D OFF, COFF, NOFF, STOFF)");

  scanner.skip_to_token();
  if (scanner.rest().starts_with("BINARY")) scanner.fail("binary OFF is not supported");

  const std::uint64_t vertex_count = scanner.read_count("the vertex count");
  const std::uint64_t face_count = scanner.read_count("the face count");
  if (scanner.skip_to_token_on_line()) scanner.read_count("the edge count", true);
  scanner.skip_line();

  // A vertex line holds at least "0 0 0\n", a face line "3 0 0 0\n" (the last newline may be missing).
  const std::size_t room = scanner.bytes_left() + 1;
  if (vertex_count > room / 6 || face_count > room / 8 || vertex_count * 6 + face_count * 8 > room)
    scanner.fail("header claims " + std::to_string(vertex_count) + " vertices and " + std::to_string(face_count) +
                 " faces, more than the " + std::to_string(scanner.bytes_left()) + " bytes that follow can hold");

  MeshBuilder builder(source);
  builder.reserve(vertex_count, face_count);
  for (std::uint64_t i = 0; i < vertex_count; ++i) {
    const double x = scanner.read_number("vertex x");
    const double y = scanner.read_number("vertex y", true);
    const double z = scanner.read_number("vertex z", true);
    builder.add_vertex(x, y, z);
    scanner.skip_line();  // normals, colours and texture coordinates
  }

  std::vector<std::uint64_t> corners;
  for (std::uint64_t f = 0; f < face_count; ++f) {
    const std::uint64_t n = scanner.read_count("a face's corner count");
    if (n < 3) scanner.fail("face with " + std::to_string(n) + " corners; a face needs 3 or more");
    if (n > scanner.bytes_left() / 2) scanner.fail("face claims " + std::to_string(n) + " corners, more than the file holds");
    corners.resize(n);
    for (std::uint64_t& corner : corners) {
      corner = scanner.read_count("a vertex index", true);
      if (corner >= vertex_count)
        scanner.fail("face refers to vertex " + std::to_string(corner) + " but there are " +
                     std::to_string(vertex_count) + " vertices");
    }
    builder.add_polygon(corners);
    scanner.skip_line();
  }
  return builder.finish();
}

}  // namespace visproxy::parsing
