#include "visproxy/mesh/mesh_parsing.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "visproxy/core/errors.h"

namespace visproxy::parsing {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

}  // namespace

TextScanner::TextScanner(std::string_view text, const std::filesystem::path& source, char comment)
    : text_(text), source_(source), comment_(comment) {}

bool TextScanner::skip_to_token() {
  while (position_ < text_.size()) {
    const char c = text_[position_];
    if (is_space(c) || c == '\n') {
      ++position_;
    } else if (comment_ != '\0' && c == comment_) {
      skip_line();
    } else {
      return true;
    }
  }
  return false;
}

bool TextScanner::skip_to_token_on_line() {
  while (position_ < text_.size() && is_space(text_[position_])) ++position_;
  if (position_ == text_.size() || text_[position_] == '\n') return false;
  if (comment_ != '\0' && text_[position_] == comment_) {
    while (position_ < text_.size() && text_[position_] != '\n') ++position_;
    return false;
  }
  return true;
}

void TextScanner::skip_line() {
  const std::size_t end = text_.find('\n', position_);
  position_ = end == std::string_view::npos ? text_.size() : end + 1;
}

std::string_view TextScanner::token() {
  if (!skip_to_token()) return {};
  return token_on_line();
}

std::string_view TextScanner::token_on_line() {
  if (!skip_to_token_on_line()) return {};
  const std::size_t start = position_;
  while (position_ < text_.size() && !is_space(text_[position_]) && text_[position_] != '\n') ++position_;
  return text_.substr(start, position_ - start);
}

std::string_view TextScanner::expect_token(std::string_view what, bool on_line) {
  const std::string_view word = on_line ? token_on_line() : token();
  if (word.empty()) fail("expected " + std::string(what) + ", found the end of the " + (on_line ? "line" : "file"));
  return word;
}

double TextScanner::read_number(std::string_view what, bool on_line) {
  const std::string_view word = expect_token(what, on_line);
  double value = 0;
  if (!parse_number(word, value)) fail("expected " + std::string(what) + ", found " + quote_token(word));
  if (!std::isfinite(value)) fail(std::string(what) + " is not finite (" + quote_token(word) + ")");
  return value;
}

std::uint64_t TextScanner::read_count(std::string_view what, bool on_line) {
  const std::string_view word = expect_token(what, on_line);
  std::int64_t value = 0;
  if (!parse_integer(word, value) || value < 0)
    fail("expected " + std::string(what) + " (a non-negative integer), found " + quote_token(word));
  return static_cast<std::uint64_t>(value);
}

std::uint64_t TextScanner::line() const {
  const std::size_t upto = std::min(position_, text_.size());
  if (upto < counted_position_) {  // moved back (seek): count again from the start
    counted_position_ = 0;
    counted_lines_ = 1;
  }
  counted_lines_ +=
      static_cast<std::uint64_t>(std::count(text_.begin() + static_cast<std::ptrdiff_t>(counted_position_),
                                            text_.begin() + static_cast<std::ptrdiff_t>(upto), '\n'));
  counted_position_ = upto;
  return counted_lines_;
}

void TextScanner::fail(std::string_view problem) const { throw InvalidInputError(source_, problem, line()); }

std::string quote_token(std::string_view token, std::size_t max_length) {
  std::string text = "'";
  for (const char c : token.substr(0, max_length)) text += (c >= 0x20 && c < 0x7f) ? c : '?';
  if (token.size() > max_length) text += "...";
  return text + "'";
}

bool parse_number(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (end != token.data() + token.size()) return false;
  if (error == std::errc::result_out_of_range) {
    // A well-formed number beyond double's range: strtod says whether it over- or underflowed.
    value = std::strtod(std::string(token).c_str(), nullptr);
    return true;
  }
  return error == std::errc();
}

bool parse_integer(std::string_view token, std::int64_t& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

void MeshBuilder::reserve(std::size_t vertices, std::size_t triangles) {
  mesh_.positions.reserve(vertices);
  mesh_.triangles.reserve(triangles);
}

void MeshBuilder::add_vertex(double x, double y, double z) {
  if (mesh_.positions.size() == std::numeric_limits<VertexIndex>::max())
    throw InvalidInputError(source_, "more than 4294967294 vertices");
  mesh_.positions.emplace_back(x, y, z);
}

void MeshBuilder::add_polygon(std::span<const std::uint64_t> corners) {
  const std::uint64_t largest_corner = *std::max_element(corners.begin(), corners.end());
  largest_index_ = std::max(largest_index_, largest_corner);
  if (corners.size() == 3) {
    // Indices that do not fit are caught by the range check in finish().
    mesh_.triangles.push_back({static_cast<VertexIndex>(std::min<std::uint64_t>(corners[0], UINT32_MAX)),
                               static_cast<VertexIndex>(std::min<std::uint64_t>(corners[1], UINT32_MAX)),
                               static_cast<VertexIndex>(std::min<std::uint64_t>(corners[2], UINT32_MAX))});
    return;
  }
  if (largest_corner < mesh_.positions.size()) {
    scratch_.assign(corners.begin(), corners.end());
    triangulate_polygon(mesh_.positions, scratch_, mesh_.triangles);
    return;
  }
  pending_starts_.push_back(pending_corners_.size());
  pending_corners_.insert(pending_corners_.end(), corners.begin(), corners.end());
}

TriangleMesh MeshBuilder::finish() {
  const std::size_t vertex_count = mesh_.positions.size();
  if (largest_index_ >= vertex_count && (!mesh_.triangles.empty() || !pending_starts_.empty()))
    throw InvalidInputError(source_, "a face refers to vertex " + std::to_string(largest_index_) +
                                         " (counting from 0), but the file has only " +
                                         std::to_string(vertex_count) + " vertices");
  pending_starts_.push_back(pending_corners_.size());
  for (std::size_t p = 0; p + 1 < pending_starts_.size(); ++p) {
    scratch_.assign(pending_corners_.begin() + static_cast<std::ptrdiff_t>(pending_starts_[p]),
                    pending_corners_.begin() + static_cast<std::ptrdiff_t>(pending_starts_[p + 1]));
    triangulate_polygon(mesh_.positions, scratch_, mesh_.triangles);
  }
  if (mesh_.triangles.empty()) throw InvalidInputError(source_, "contains no faces");
  return std::move(mesh_);
}

}  // namespace visproxy::parsing
