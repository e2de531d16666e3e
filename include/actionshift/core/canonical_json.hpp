#pragma once
/// \file Canonical JSON: byte-compatible with Python's
/// `json.dumps(obj, sort_keys=True, separators=(",", ":"))` (ensure_ascii on), which is what the
/// reference hashes. Floats print as Python's `repr`: shortest round-trip digits, always with a
/// decimal point or exponent (`1.0`, `0.75`, `1e-05`, `1e+16`).

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>

namespace actionshift {

/// Python `repr(float)` of a finite double. Throws std::invalid_argument for NaN or infinity
/// (canonical JSON has no representation for them; Python would write `NaN`, which is not JSON).
inline std::string python_float_repr(double x) {
  if (!std::isfinite(x)) throw std::invalid_argument("canonical JSON: non-finite float");
  if (x == 0.0) return std::signbit(x) ? "-0.0" : "0.0";
  // shortest round-trip digits in scientific form: [-]d[.ddd]e[+-]XX
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::scientific);
  std::string_view sci(buf, static_cast<std::size_t>(res.ptr - buf));
  std::string out;
  if (sci.front() == '-') {
    out.push_back('-');
    sci.remove_prefix(1);
  }
  const auto epos = sci.find('e');
  std::string digits;
  for (char c : sci.substr(0, epos))
    if (c != '.') digits.push_back(c);
  int exp10 = 0;
  std::from_chars(sci.data() + epos + 1 + (sci[epos + 1] == '+' ? 1 : 0), sci.data() + sci.size(), exp10);
  const int n = static_cast<int>(digits.size());
  if (exp10 >= -4 && exp10 < 16) {  // Python repr: fixed notation iff -4 <= exp < 16
    if (exp10 >= 0) {
      if (n <= exp10 + 1) {
        out += digits + std::string(static_cast<std::size_t>(exp10 + 1 - n), '0') + ".0";
      } else {
        out += digits.substr(0, static_cast<std::size_t>(exp10 + 1)) + "." + digits.substr(static_cast<std::size_t>(exp10 + 1));
      }
    } else {
      out += "0." + std::string(static_cast<std::size_t>(-exp10 - 1), '0') + digits;
    }
  } else {
    out += digits.substr(0, 1);
    if (n > 1) out += "." + digits.substr(1);
    out += 'e';
    out += exp10 < 0 ? '-' : '+';
    const int a = exp10 < 0 ? -exp10 : exp10;
    if (a < 10) out += '0';
    out += std::to_string(a);
  }
  return out;
}

namespace detail {
inline void canonical_dump_into(const nlohmann::json& j, std::string& out) {
  using T = nlohmann::json::value_t;
  switch (j.type()) {
    case T::object: {
      out.push_back('{');
      bool first = true;
      for (auto it = j.cbegin(); it != j.cend(); ++it) {  // std::map: keys already in byte order
        if (!first) out.push_back(',');
        first = false;
        out += nlohmann::json(it.key()).dump(-1, ' ', true);
        out.push_back(':');
        canonical_dump_into(it.value(), out);
      }
      out.push_back('}');
      return;
    }
    case T::array: {
      out.push_back('[');
      bool first = true;
      for (const auto& v : j) {
        if (!first) out.push_back(',');
        first = false;
        canonical_dump_into(v, out);
      }
      out.push_back(']');
      return;
    }
    case T::number_float:
      out += python_float_repr(j.get<double>());
      return;
    case T::string:
      out += j.dump(-1, ' ', true);  // ensure_ascii, as Python's default
      return;
    default:  // null, boolean, integers
      out += j.dump();
      return;
  }
}
}  // namespace detail

/// Canonical compact serialisation (sorted keys, no whitespace, Python-repr floats).
inline std::string canonical_dump(const nlohmann::json& j) {
  std::string out;
  detail::canonical_dump_into(j, out);
  return out;
}

}  // namespace actionshift
