#pragma once
/// \file
/// The one way ActionShift parses JSON that came from outside (files, lines of files, other processes,
/// command-line arguments): nesting is limited, and every failure, including nlohmann's
/// `out_of_range` for numbers that overflow a double (`1e999`), becomes an InputError naming the
/// source and, where known, the field being read.

#include "actionshift/core/error.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

namespace actionshift {

/// Deepest array/object nesting accepted in external JSON. ActionShift's own files need fewer than
/// 10 levels; the limit keeps every recursive walk over a parsed value (copies, dumps, hashing,
/// comparisons) far from the stack's end.
inline constexpr int kMaxJsonDepth = 64;

namespace detail {

// field path of the current parse position from the keys seen so far, e.g. `methods[].params.k`
inline std::string json_field_path(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) {
    if (!out.empty() && n != "[]") out += '.';
    out += n;
  }
  return out;
}

// nlohmann's message without its "[json.exception.<kind>.<id>] " prefix and byte-offset chatter;
// the text it quotes as "last read" (an unterminated string: all of it) is cut to 80 bytes
inline std::string json_reason(const std::string& what) {
  const auto close = what.find("] ");
  std::string r = close == std::string::npos || what.rfind("[json.exception.", 0) != 0 ? what : what.substr(close + 2);
  static constexpr std::string_view kLastRead = "last read: '";
  if (const auto at = r.find(kLastRead); at != std::string::npos) {
    const auto from = at + kLastRead.size();
    // the quoted text ends at "'; expected …" if nlohmann names what it expected, else at the end
    auto to = r.find("'; expected", from);
    if (to == std::string::npos) to = !r.empty() && r.back() == '\'' ? r.size() - 1 : r.size();
    if (to > from + 80) r = r.substr(0, from) + printable_input(std::string_view(r).substr(from, to - from), 80) + r.substr(to);
  }
  return r;
}

}  // namespace detail

/// A JSON value quoted into a one-line error message: compact, cut after `max_bytes`, and never
/// throwing (a string holding bytes that are not UTF-8, e.g. from YAML or a command line, is dumped
/// with U+FFFD where plain dump() would throw type_error 316).
inline std::string json_for_message(const nlohmann::json& v, std::size_t max_bytes = 80) {
  return printable_input(v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), max_bytes);
}

/// Parse `text` read from `source`. `field` prefixes the field path in errors (e.g. the name of the
/// argument or header the text came from). Never recurses on the input's structure.
/// throws InputError(source, field path, reason) for syntax errors, nesting deeper than
/// `max_depth`, a key repeated within one object, and numbers outside the range of a double.
inline nlohmann::json parse_json_input(std::string_view text, const std::string& source, const std::string& field = "",
                                       int max_depth = kMaxJsonDepth) {
  std::vector<std::string> names;
  if (!field.empty()) names.push_back(field);
  // the keys seen so far in each open object, innermost last: a repeated key is refused (nlohmann
  // would keep the last value silently, so `{"scale": 1, "scale": -1}` would read as -1)
  // (a hash set per object: a vector compared every key with all before it, quadratic in the key count)
  std::vector<std::unordered_set<std::string>> open_keys;
  const std::size_t base = names.size();
  const auto at = [&](int depth) { return base + static_cast<std::size_t>(depth > 0 ? depth : 0); };
  const nlohmann::json::parser_callback_t track = [&](int depth, nlohmann::json::parse_event_t event,
                                                      nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    switch (event) {
      case E::object_start:
      case E::array_start:
        if (depth >= max_depth) {
          throw InputError(source, detail::json_field_path(names),
                           "JSON nested deeper than " + std::to_string(max_depth) + " levels");
        }
        names.resize(at(depth));
        if (event == E::array_start) names.emplace_back("[]");
        if (event == E::object_start) open_keys.emplace_back();
        break;
      case E::key: {
        names.resize(at(depth - 1));
        names.push_back(parsed.is_string() ? parsed.get<std::string>() : std::string("?"));
        if (!open_keys.empty() && parsed.is_string()) {
          if (!open_keys.back().insert(parsed.get_ref<const std::string&>()).second)
            throw InputError(source, printable_input(detail::json_field_path(names), 200), "duplicate key in one object");
        }
        break;
      }
      case E::object_end:
        if (!open_keys.empty()) open_keys.pop_back();
        names.resize(at(depth));
        break;
      case E::array_end:
        names.resize(at(depth));
        break;
      case E::value:
        break;
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text.begin(), text.end(), track, /*allow_exceptions=*/true);
  } catch (const InputError&) {
    throw;
  } catch (const nlohmann::json::out_of_range& e) {
    throw InputError(source, detail::json_field_path(names), "number out of range: " + detail::json_reason(e.what()));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(source, detail::json_field_path(names), "not valid JSON: " + detail::json_reason(e.what()));
  }
}

}  // namespace actionshift
