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

#include "visproxy/core/files.h"
#include "schema_support.h"

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
    if (entry.contains("measure")) {
      const nlohmann::json& cost_schema = entry_schema.at("properties").at("measure").at("properties").at("cost_ns_per_ray");
      const nlohmann::json& cost = entry.at("measure").at("cost_ns_per_ray");
      for (const auto& key : cost_schema.at("required")) EXPECT_TRUE(cost.contains(key.get<std::string>())) << "cost." << key;
      for (const auto& [key, value] : cost.items())
        EXPECT_TRUE(cost_schema.at("properties").contains(key) ||
                    cost_schema.at("required").dump().find('"' + key + '"') != std::string::npos)
            << "cost_ns_per_ray." << key;
      if (cost.contains("work")) check(cost.at("work"), s.at("$defs").at("work_per_ray"), "work");
      if (cost.contains("predicted")) check(cost.at("predicted"), cost_schema.at("properties").at("predicted"), "predicted");
    }
  }
  if (manifest.contains("cost_model")) {
    check(manifest.at("cost_model"), s.at("properties").at("cost_model"), "cost_model");
    if (manifest.at("cost_model").contains("ns"))
      check(manifest.at("cost_model").at("ns"), s.at("properties").at("cost_model").at("properties").at("ns"), "cost_model.ns");
  }
}

}  // namespace visproxy::testing
