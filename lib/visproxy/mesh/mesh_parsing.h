#pragma once
// Shared machinery of the mesh readers (internal to lib/visproxy/mesh).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/core/errors.h"
#include "visproxy/mesh/triangle_mesh.h"

namespace visproxy::parsing {

/// A cursor over the bytes of a text format. Errors name the source and the line.
class TextScanner {
 public:
  /// `comment` starts a comment that runs to the end of the line ('\0' for none).
  TextScanner(std::string_view text, const std::filesystem::path& source, char comment = '\0');

  /// Skips spaces, newlines and comments; true if any byte is left.
  bool skip_to_token();
  /// Skips spaces and a comment on the current line; true if the line has a token left.
  bool skip_to_token_on_line();
  /// Moves past the end of the current line.
  void skip_line();
  /// The next whitespace-delimited token, crossing lines; empty at the end of the text.
  std::string_view token();
  /// The next token on the current line; empty at the end of the line.
  std::string_view token_on_line();

  /// Reads a finite number from the next token; `what` names it in errors.
  double read_number(std::string_view what, bool on_line = false);
  /// Reads a non-negative integer from the next token.
  std::uint64_t read_count(std::string_view what, bool on_line = false);

  std::size_t bytes_left() const { return text_.size() - position_; }
  std::size_t position() const { return position_; }
  void seek(std::size_t position) { position_ = position; }
  std::string_view rest() const { return text_.substr(position_); }
  /// The current line, from 1. Linear in the distance moved since the last call, so asking
  /// once per line of a whole file costs one pass over it.
  std::uint64_t line() const;

  /// Throws InvalidInputError naming the source and the current line.
  [[noreturn]] void fail(std::string_view problem) const;

 private:
  // The next token, or a failure naming `what` at the end of the line or file.
  std::string_view expect_token(std::string_view what, bool on_line);

  std::string_view text_;
  std::size_t position_ = 0;
  const std::filesystem::path& source_;
  char comment_;
  mutable std::size_t counted_position_ = 0;  // line() has counted the newlines before here
  mutable std::uint64_t counted_lines_ = 1;
};

/// A token as it may appear in an error message: at most `max_length` characters (then
/// "..."), with non-printable bytes shown as '?', in single quotes.
std::string quote_token(std::string_view token, std::size_t max_length = 40);

/// Parses a whole token as a number; false if it is not one (non-finite values parse).
bool parse_number(std::string_view token, double& value);
/// Parses a whole token as a signed integer; false if it is not one.
bool parse_integer(std::string_view token, std::int64_t& value);

/// Collects vertices and polygons, triangulates, and checks the result.
class MeshBuilder {
 public:
  explicit MeshBuilder(const std::filesystem::path& source) : source_(source) {}

  void reserve(std::size_t vertices, std::size_t triangles);
  std::size_t vertex_count() const { return mesh_.positions.size(); }
  /// Adds a vertex; the caller has checked that the coordinates are finite.
  void add_vertex(double x, double y, double z);
  /// Adds a face of three or more corners. Polygons are triangulated at once when their
  /// corners are known, otherwise (OBJ may refer to later vertices) in finish().
  /// Indices are range-checked in finish().
  void add_polygon(std::span<const std::uint64_t> corners);
  /// Triangulates pending polygons and checks indices and that there is a face. Call once.
  TriangleMesh finish();

 private:
  const std::filesystem::path& source_;
  TriangleMesh mesh_;
  std::vector<std::uint64_t> pending_corners_;  // polygons waiting for their vertices,
  std::vector<std::size_t> pending_starts_;     // each starting at this offset
  std::vector<VertexIndex> scratch_;
  std::uint64_t largest_index_ = 0;
};

/// Appends a triangulation of the polygon with the given corners (indices into
/// `positions`, three or more) to `triangles`: ear clipping in the plane of the polygon's
/// Newell normal, so non-convex planar polygons come out right; a fan for degenerate
/// polygons, polygons ear clipping cannot finish, and polygons of more than 256 corners.
void triangulate_polygon(const std::vector<Vertex>& positions, std::span<const VertexIndex> corners,
                         std::vector<Triangle>& triangles);

TriangleMesh parse_obj(std::string_view bytes, const std::filesystem::path& source);
TriangleMesh parse_ply(std::string_view bytes, const std::filesystem::path& source, const WarningHandler& on_warning);
TriangleMesh parse_off(std::string_view bytes, const std::filesystem::path& source);
TriangleMesh parse_stl(std::string_view bytes, const std::filesystem::path& source);

/// The extension of `path` in lower case, with its dot (".gltf"); empty when it has none.
std::string lowercase_extension(const std::filesystem::path& path);

/// Whether Assimp reads files with this extension (read_assimp.cpp).
bool assimp_reads(const std::filesystem::path& path);
/// Runs `read` (which calls Assimp) in a child process limited to 1 GiB plus 64 x
/// `input_bytes` of memory more than this process holds (VISPROXY_ASSIMP_MEMORY_MB
/// overrides it) and 20 s plus 1 s per MB of input of processor time (VISPROXY_ASSIMP_SECONDS
/// overrides it), and returns the mesh it made. Its refusal,
/// a crash or a limit reached throws InvalidInputError naming `source`. Where no process
/// can be started, `read` runs here.
TriangleMesh assimp_isolated(const std::filesystem::path& source, std::uint64_t input_bytes,
                             const std::function<TriangleMesh()>& read);
/// The same for any answer: runs `read` in the child and returns the bytes it made.
std::string assimp_isolated_bytes(const std::filesystem::path& source, std::uint64_t input_bytes,
                                  const std::function<std::string()>& read);
/// The bytes of input a file counts for those limits: a .gltf's whole folder (its buffers
/// and images lie beside it), else the file's size.
std::uint64_t assimp_input_bytes(const std::filesystem::path& path);
/// A file in a format Assimp reads, its nodes flattened into one mesh in world space.
/// Reads from the file system, so that glTF's external buffers are found beside it.
TriangleMesh read_assimp_file(const std::filesystem::path& path);
/// The same from bytes; the extension of `source` tells Assimp the format.
TriangleMesh parse_assimp(std::string_view bytes, const std::filesystem::path& source);

}  // namespace visproxy::parsing
