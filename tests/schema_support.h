#pragma once
// The JSON schemas in data/schemas, read for tests that check files against them.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "visproxy/core/files.h"

namespace visproxy::testing {

inline nlohmann::json read_schema(const std::string& name) {
  return nlohmann::json::parse(read_file(std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/schemas" / name));
}

/// A structural check of `value` against `part` of `schema`: every required key present,
/// every key of an object described (by "properties" or "additionalProperties"), constants
/// and enumerations matched, arrays' items checked, "$ref"s followed (within the schema, or
/// to another schema file of data/schemas named by its file name).
/// Alternatives ("oneOf") are descended into when exactly one of them names the value's
/// JSON type (an object or null, say); else they are not checked.
inline void expect_described(const nlohmann::json& value, const nlohmann::json& schema, const nlohmann::json& part,
                             const std::string& where) {
  if (part.contains("oneOf")) {
    const std::string type = value.is_null()     ? "null"
                             : value.is_object() ? "object"
                             : value.is_array()  ? "array"
                             : value.is_string() ? "string"
                             : value.is_boolean() ? "boolean"
                             : value.is_number_integer() ? "integer"
                                                         : "number";
    const nlohmann::json* chosen = nullptr;
    int matching = 0;
    for (const auto& alternative : part.at("oneOf"))
      if (alternative.value("type", std::string()) == type) chosen = &alternative, ++matching;
    if (matching == 1) return expect_described(value, schema, *chosen, where);
    return;
  }
  if (part.contains("$ref")) {
    const std::string ref = part.at("$ref");  // "#/$defs/NAME", or another schema of data/schemas by file name
    if (ref.rfind("#", 0) != 0) {
      const nlohmann::json other = read_schema(ref);
      return expect_described(value, other, other, where);
    }
    return expect_described(value, schema, schema.at("$defs").at(ref.substr(ref.rfind('/') + 1)), where);
  }
  if (part.contains("const")) {
    EXPECT_EQ(value, part.at("const")) << where;
  }
  if (part.contains("enum")) {
    const auto& options = part.at("enum");
    EXPECT_NE(std::find(options.begin(), options.end(), value), options.end()) << where << " = " << value;
  }
  if (value.is_object()) {
    if (part.contains("required")) {
      for (const auto& key : part.at("required"))
        EXPECT_TRUE(value.contains(key.get<std::string>())) << where << "." << key;
    }
    for (const auto& [key, item] : value.items()) {
      if (part.contains("properties") && part.at("properties").contains(key)) {
        expect_described(item, schema, part.at("properties").at(key), where + "." + key);
      } else if (part.contains("additionalProperties")) {
        expect_described(item, schema, part.at("additionalProperties"), where + "." + key);
      } else {
        ADD_FAILURE() << where << "." << key << " is not described by the schema";
      }
    }
  } else if (value.is_array() && part.contains("items")) {
    for (std::size_t i = 0; i < value.size(); ++i)
      expect_described(value[i], schema, part.at("items"), where + "[" + std::to_string(i) + "]");
  }
}

inline void expect_described(const nlohmann::json& value, const std::string& schema_name) {
  const nlohmann::json schema = read_schema(schema_name);
  expect_described(value, schema, schema, schema_name);
}

}  // namespace visproxy::testing
