#pragma once
// Runs the visproxy executable as a user would and captures what it prints.

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include <gtest/gtest.h>

#include "core/files.h"

namespace visproxy::testing {

struct CommandResult {
  int exit_code = -1;
  std::string out;  // standard output
  std::string err;  // standard error
};

/// Runs `visproxy ARGUMENTS` through the shell; ARGUMENTS must already be quoted.
inline CommandResult run_visproxy(const std::string& arguments) {
  const auto err_path = std::filesystem::temp_directory_path() /
                        ("visproxy-cli-stderr-" + std::to_string(::getpid()) + ".txt");
  const std::string command = std::string("'") + VISPROXY_CLI + "' " + arguments + " 2>'" + err_path.string() + "'";
  CommandResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  for (std::size_t got; (got = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0;) result.out.append(buffer.data(), got);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (FILE* err = std::fopen(err_path.c_str(), "rb")) {
    for (std::size_t got; (got = std::fread(buffer.data(), 1, buffer.size(), err)) > 0;) result.err.append(buffer.data(), got);
    std::fclose(err);
  }
  std::filesystem::remove(err_path);
  return result;
}

inline nlohmann::json manifest_schema() {
  return nlohmann::json::parse(read_file(std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/schemas/manifest.schema.json"));
}

/// Every required key is present and every present key is described, at the top level,
/// in `mesh`, in `options` and in each proxy entry with its `error`, `verify` and
/// `measure` objects.
inline void expect_matches_schema(const nlohmann::json& manifest) {
  const nlohmann::json s = manifest_schema();
  auto check = [](const nlohmann::json& object, const nlohmann::json& part, const std::string& where) {
    for (const auto& key : part.at("required")) EXPECT_TRUE(object.contains(key.get<std::string>())) << where << "." << key;
    for (const auto& [key, value] : object.items()) EXPECT_TRUE(part.at("properties").contains(key)) << where << "." << key;
  };
  check(manifest, s, "manifest");
  check(manifest.at("mesh"), s.at("properties").at("mesh"), "mesh");
  check(manifest.at("options"), s.at("properties").at("options"), "options");
  const nlohmann::json& entry_schema = s.at("properties").at("proxies").at("items");
  for (const nlohmann::json& entry : manifest.at("proxies")) {
    check(entry, entry_schema, entry.at("name").get<std::string>());
    for (const char* part : {"error", "verify", "measure"})
      if (entry.contains(part)) check(entry.at(part), entry_schema.at("properties").at(part), part);
  }
}

inline nlohmann::json read_schema(const std::string& name) {
  return nlohmann::json::parse(read_file(std::filesystem::path(VISPROXY_SOURCE_DIR) / "data/schemas" / name));
}

/// A structural check of `value` against `part` of `schema`: every required key present,
/// every key of an object described (by "properties" or "additionalProperties"), constants
/// and enumerations matched, arrays' items checked, "$ref"s within the schema followed.
/// Alternatives ("oneOf") are not descended into.
inline void expect_described(const nlohmann::json& value, const nlohmann::json& schema, const nlohmann::json& part,
                             const std::string& where) {
  if (part.contains("$ref")) {
    const std::string ref = part.at("$ref");  // "#/$defs/NAME"
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
      for (const auto& key : part.at("required")) EXPECT_TRUE(value.contains(key.get<std::string>())) << where << "." << key;
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
    for (std::size_t i = 0; i < value.size(); ++i) expect_described(value[i], schema, part.at("items"), where + "[" + std::to_string(i) + "]");
  }
}

inline void expect_described(const nlohmann::json& value, const std::string& schema_name) {
  const nlohmann::json schema = read_schema(schema_name);
  expect_described(value, schema, schema, schema_name);
}

}  // namespace visproxy::testing
