// Wavefront OBJ: `v` and `f` records; everything else (texture coordinates, normals,
// groups, materials, lines, points) is skipped.

#include <string>

#include "visproxy/mesh/mesh_parsing.h"

namespace visproxy::parsing {

TriangleMesh parse_obj(std::string_view bytes, const std::filesystem::path& source) {
  TextScanner scanner(bytes, source, '#');
  MeshBuilder builder(source);
  // Each record is at least "v 0 0 0" or "f 1 2 3": a cheap upper bound for reservations.
  builder.reserve(bytes.size() / 64, bytes.size() / 32);
  std::vector<std::uint64_t> corners;

  while (scanner.skip_to_token()) {
    const std::string_view keyword = scanner.token_on_line();
    if (keyword == "v") {
      const double x = scanner.read_number("vertex x", true);
      const double y = scanner.read_number("vertex y", true);
      const double z = scanner.read_number("vertex z", true);
      builder.add_vertex(x, y, z);
    } else if (keyword == "f") {
      corners.clear();
      const auto defined = static_cast<std::int64_t>(builder.vertex_count());
      for (std::string_view word = scanner.token_on_line(); !word.empty(); word = scanner.token_on_line()) {
        const std::string_view position = word.substr(0, word.find('/'));
        std::int64_t index = 0;
        if (!parse_integer(position, index))
          scanner.fail("face corner " + quote_token(word) + " does not start with a vertex index");
        if (index == 0) scanner.fail("face corner refers to vertex 0; OBJ indices start at 1");
        if (index < 0) {
          if (index < -defined)
            scanner.fail("relative index " + std::to_string(index) + " reaches before the first vertex (" +
                         std::to_string(defined) + " defined so far)");
          index += defined;
        } else {
          index -= 1;
        }
        corners.push_back(static_cast<std::uint64_t>(index));
      }
      if (corners.size() < 3) scanner.fail("face with " + std::to_string(corners.size()) + " corners; a face needs 3 or more");
      builder.add_polygon(corners);
    }
    scanner.skip_line();
  }
  return builder.finish();
}

}  // namespace visproxy::parsing
