#pragma once
// Named choices: one table of names per enum (choice_names<Enum>, specialised beside the
// enum), from which its name, its parsing and the help's "{a, b, c}" are all read.

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "visproxy/core/errors.h"

namespace visproxy {

/// The names of a choice's values, in the order the CLI and the help list them: one table
/// per enum, which name_of, parse_choice and the help's "{a, b, c}" all read.
template <class Enum>
const std::vector<std::pair<std::string_view, Enum>>& choice_names();

/// The name of `value` in choice_names<Enum>().
template <class Enum>
std::string_view name_of(Enum value) {
  for (const auto& [name, v] : choice_names<Enum>())
    if (v == value) return name;
  return choice_names<Enum>().front().first;
}

/// "{a, b, c}": the names of a choice, for help texts and errors.
template <class Enum>
std::string choice_list() {
  std::string text = "{";
  for (const auto& [name, v] : choice_names<Enum>()) text += (text.size() > 1 ? ", " : "") + std::string(name);
  return text + "}";
}

/// The value named `text` (case-insensitive), or nullopt.
template <class Enum>
std::optional<Enum> find_choice(std::string_view text) {
  std::string lower(text);
  for (char& c : lower) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  for (const auto& [name, value] : choice_names<Enum>())
    if (lower == name) return value;
  return std::nullopt;
}

/// The value named `text` (case-insensitive); throws OptionError naming `option` and the
/// names it accepts otherwise: "--visibility: 'foo' is not one of {exact, stochastic, bounds, spheres}".
template <class Enum>
Enum parse_choice(std::string_view option, std::string_view text) {
  if (const std::optional<Enum> value = find_choice<Enum>(text)) return *value;
  throw OptionError(option, "'" + std::string(text) + "' is not one of " + choice_list<Enum>());
}

}  // namespace visproxy
