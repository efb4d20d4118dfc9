#include "visproxy/proxy/proxy_spec.h"

#include <set>

#include "visproxy/core/errors.h"

namespace visproxy {

std::string ProxySpec::name() const { return output_names().front(); }

std::vector<std::string> ProxySpec::output_names() const {
  if (method->primitives == PrimitiveType::sphere) {
    std::vector<std::string> names;
    for (const std::size_t level : levels) names.push_back(std::string(method->name) + "-" + std::to_string(level));
    return names;
  }
  std::string name;
  for (const char c : text) name += c == ':' || c == ',' ? std::string("-") : c == '%' ? std::string("pct") : std::string(1, c);
  return {name};
}

ProxySpec parse_proxy_spec(std::string_view text) {
  ProxySpec spec;
  spec.text = std::string(text);
  const std::size_t colon = text.find(':');
  const std::string_view name = text.substr(0, colon);
  const bool has_argument = colon != std::string_view::npos;
  const std::string_view argument = has_argument ? text.substr(colon + 1) : std::string_view();
  using Argument = ProxyMethodRow::Argument;
  const ProxyMethodRow* match = nullptr;
  std::string grammars, forms;
  for (const ProxyMethodRow& row : proxy_methods()) {
    grammars += (grammars.empty() ? "" : ", ") + std::string(row.grammar);
    if (row.name != name) continue;
    forms += (forms.empty() ? "" : " or ") + std::string(row.grammar);
    const bool given = has_argument && !argument.empty();
    const bool fits = row.argument == Argument::optional ? !(has_argument && argument.empty())
                      : row.argument == Argument::required ? given
                                                           : !has_argument;
    if (fits) match = &row;
  }
  if (forms.empty()) fail_spec(text, "unknown proxy '" + std::string(name) + "' (expected " + grammars + ")");
  if (!match) {
    if (has_argument && argument.empty()) fail_spec(text, "expected " + forms);
    fail_spec(text, has_argument ? std::string(name) + " takes no parameters" : "expected " + forms);
  }
  spec.method = match;
  match->parse(spec, argument);
  return spec;
}

std::vector<ProxySpec> default_proxy_specs() {
  return parse_proxy_specs(
      {"aabb", "obb", "hull", "hull:32", "wrap", "outer:512", "quadric:512", "cluster:0.03", "inside:40", "spheres:100"});
}

std::vector<ProxySpec> parse_proxy_specs(const std::vector<std::string>& texts) {
  std::vector<ProxySpec> specs;
  std::set<std::string> names;
  for (const std::string& text : texts) {
    ProxySpec spec = parse_proxy_spec(text);
    for (const std::string& name : spec.output_names())
      if (!names.insert(name).second) fail_spec(text, "the proxy '" + name + "' is asked for twice");
    specs.push_back(std::move(spec));
  }
  return specs;
}

}  // namespace visproxy
