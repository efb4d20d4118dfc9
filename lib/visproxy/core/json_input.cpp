#include "visproxy/core/json_input.h"

#include <algorithm>
#include <cmath>

#include "visproxy/core/errors.h"

namespace visproxy {

using nlohmann::json;

std::string json_member_path(const std::string& path, std::string_view key) {
  const bool plain = !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
  if (!plain) return path + "[" + json_quoted(key) + "]";
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string json_index_path(const std::string& path, std::size_t index) {
  return path + "[" + std::to_string(index) + "]";
}

std::string json_quoted(std::string_view text) {
  return json(std::string(text)).dump(-1, ' ', false, json::error_handler_t::replace);
}

json JsonInput::parse(std::string_view text) const {
  try {
    return json::parse(text.begin(), text.end());
  } catch (const json::parse_error& error) {
    // error.byte counts from 1 and may point one past the end of the text.
    const std::size_t upto = std::min<std::size_t>(error.byte > 0 ? error.byte - 1 : 0, text.size());
    const auto line = 1 + static_cast<std::uint64_t>(
                              std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(upto), '\n'));
    throw InvalidInputError(file_, "not valid JSON", line);
  } catch (const json::exception&) {  // a number beyond double's range
    throw InvalidInputError(file_, "not valid JSON");
  }
}

void JsonInput::fail(const std::string& where, std::string_view problem) const {
  throw InvalidInputError(file_, where.empty() ? std::string(problem) : where + ": " + std::string(problem));
}

const json& JsonInput::object(const json& value, const std::string& where) const {
  if (!value.is_object()) fail(where, "expected an object");
  return value;
}

const json& JsonInput::member(const json& object, const char* key, const std::string& where) const {
  const json* value = optional_member(object, key, where);
  if (!value) fail(where, std::string("missing \"") + key + "\"");
  return *value;
}

const json* JsonInput::optional_member(const json& value, const char* key, const std::string& where) const {
  const auto it = object(value, where).find(key);
  return it == value.end() ? nullptr : &*it;
}

double JsonInput::number(const json& value, const std::string& where) const {
  if (!value.is_number()) fail(where, "expected a number");
  const double x = value.get<double>();
  if (!std::isfinite(x)) fail(where, "not finite");
  return x;
}

double JsonInput::positive_number(const json& value, const std::string& where) const {
  if (!value.is_number() || !(value.get<double>() > 0) || !std::isfinite(value.get<double>()))
    fail(where, "must be a positive number");
  return value.get<double>();
}

std::uint64_t JsonInput::integer(const json& value, const std::string& where, std::uint64_t min,
                                 std::uint64_t max) const {
  // The parser holds every integer written without a minus sign as unsigned.
  if (!value.is_number_unsigned() || value.get<std::uint64_t>() < min || value.get<std::uint64_t>() > max)
    fail(where, "expected an integer from " + std::to_string(min) + " to " + std::to_string(max));
  return value.get<std::uint64_t>();
}

std::uint64_t JsonInput::count(const json& value, const std::string& where) const {
  if (!value.is_number_unsigned()) fail(where, "expected a count (a non-negative integer)");
  return value.get<std::uint64_t>();
}

std::array<double, 3> JsonInput::triple(const json& value, const std::string& where) const {
  if (!value.is_array() || value.size() != 3 ||
      !std::all_of(value.begin(), value.end(), [](const json& x) { return x.is_number(); }))
    fail(where, "expected an array of 3 numbers");
  return {number(value[0], where), number(value[1], where), number(value[2], where)};
}

const std::string& JsonInput::string(const json& value, const std::string& where) const {
  if (!value.is_string()) fail(where, "must be a string");
  return value.get_ref<const std::string&>();
}

bool JsonInput::boolean(const json& value, const std::string& where) const {
  if (!value.is_boolean()) fail(where, "must be true or false");
  return value.get<bool>();
}

}  // namespace visproxy
