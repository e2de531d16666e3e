#pragma once
// private to the render layer: escaping text for SVG and HTML (one routine for figures and the report)

#include <string>

namespace actionshift::render::detail {

/// `&`, `<`, `>` and `"` as XML entities; everything else unchanged.
inline std::string xml_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace actionshift::render::detail
