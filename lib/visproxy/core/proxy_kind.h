#pragma once
// The three kinds of visibility proxy.

#include <string_view>

namespace visproxy {

/// What a proxy promises about the geometry it stands in for (Billen et al., section 3):
/// an outside proxy contains it, an inside proxy lies within it, a general proxy neither.
enum class ProxyKind { outside, inside, general };

constexpr std::string_view kind_name(ProxyKind kind) {
  switch (kind) {
    case ProxyKind::outside: return "outside";
    case ProxyKind::inside: return "inside";
    case ProxyKind::general: return "general";
  }
  return "general";
}

}  // namespace visproxy
