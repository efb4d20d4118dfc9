#pragma once
// Reading visproxy's JSON files (scenes, manifests, sphere sets) with errors that name the
// file and the JSON path of the value at fault, on one line:
//   scene.json: instances[2].transform.fit.height: must be a positive number
// A path is empty for the document itself; a member whose key is a plain identifier is
// `.key` (no dot at the start), any other `["key"]`; an array element is `[i]`.

#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace visproxy {

/// `path` followed by the member `key`: "instances[2]" and "transform" give
/// "instances[2].transform"; "meshes" and "my mesh" give `meshes["my mesh"]`.
std::string json_member_path(const std::string& path, std::string_view key);
/// `path` followed by the array element `index`: "lights" and 0 give "lights[0]".
std::string json_index_path(const std::string& path, std::size_t index);
/// `text` as a JSON string literal, quotes and control characters escaped (invalid UTF-8
/// replaced), so that a name from a file keeps an error message on one line.
std::string json_quoted(std::string_view text);

/// The checks of one JSON file. Every check returns the value it accepts or throws
/// InvalidInputError(file, "PATH: problem").
class JsonInput {
 public:
  explicit JsonInput(std::filesystem::path file) : file_(std::move(file)) {}

  const std::filesystem::path& file() const { return file_; }

  /// Parses a whole document; throws "FILE:LINE: not valid JSON" (numbers beyond double's
  /// range included).
  nlohmann::json parse(std::string_view text) const;

  /// Throws InvalidInputError(file, "WHERE: problem"), or "problem" when `where` is empty.
  [[noreturn]] void fail(const std::string& where, std::string_view problem) const;

  /// Checks that `value` is an object.
  const nlohmann::json& object(const nlohmann::json& value, const std::string& where) const;
  /// The member `key` of the object at `where`: "WHERE: missing "KEY"" when it is absent.
  const nlohmann::json& member(const nlohmann::json& object, const char* key, const std::string& where) const;
  /// The same, or nullptr when it is absent.
  const nlohmann::json* optional_member(const nlohmann::json& object, const char* key, const std::string& where) const;

  /// A number ("expected a number"); JSON cannot hold infinities or NaN.
  double number(const nlohmann::json& value, const std::string& where) const;
  /// A number above zero ("must be a positive number").
  double positive_number(const nlohmann::json& value, const std::string& where) const;
  /// A whole number from `min` to `max` ("expected an integer from MIN to MAX").
  std::uint64_t integer(const nlohmann::json& value, const std::string& where, std::uint64_t min,
                        std::uint64_t max) const;
  /// A non-negative whole number ("expected a count (a non-negative integer)").
  std::uint64_t count(const nlohmann::json& value, const std::string& where) const;
  /// An array of three numbers ("expected an array of 3 numbers").
  std::array<double, 3> triple(const nlohmann::json& value, const std::string& where) const;
  /// A string ("must be a string").
  const std::string& string(const nlohmann::json& value, const std::string& where) const;
  /// true or false ("must be true or false").
  bool boolean(const nlohmann::json& value, const std::string& where) const;

 private:
  std::filesystem::path file_;
};

}  // namespace visproxy
