#pragma once
/// \file Error types and boundary checks shared by every layer.

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace actionshift {

namespace detail {

// length of the well-formed UTF-8 sequence starting at s[i] (RFC 3629: no overlong forms, no
// surrogates, nothing above U+10FFFF), or 0 if the bytes there are not one
inline std::size_t utf8_sequence_length(std::string_view s, std::size_t i) noexcept {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const auto cont = [&](std::size_t k, unsigned lo, unsigned hi) { return k < s.size() && byte(k) >= lo && byte(k) <= hi; };
  const unsigned c = byte(i);
  if (c < 0x80) return 1;
  if (c >= 0xc2 && c <= 0xdf) return cont(i + 1, 0x80, 0xbf) ? 2 : 0;
  if (c >= 0xe0 && c <= 0xef)
    return cont(i + 1, c == 0xe0 ? 0xa0 : 0x80, c == 0xed ? 0x9f : 0xbf) && cont(i + 2, 0x80, 0xbf) ? 3 : 0;
  if (c >= 0xf0 && c <= 0xf4)
    return cont(i + 1, c == 0xf0 ? 0x90 : 0x80, c == 0xf4 ? 0x8f : 0xbf) && cont(i + 2, 0x80, 0xbf) && cont(i + 3, 0x80, 0xbf)
               ? 4
               : 0;
  return 0;
}

}  // namespace detail

/// Byte offset of the first byte of `s` that is not part of well-formed UTF-8, or npos if all is.
inline std::size_t invalid_utf8_offset(std::string_view s) noexcept {
  for (std::size_t i = 0; i < s.size();) {
    const std::size_t n = detail::utf8_sequence_length(s, i);
    if (n == 0) return i;
    i += n;
  }
  return std::string_view::npos;
}

/// User text made safe to echo inside a one-line message: control characters become escapes (`\n`,
/// `\t`, `\r`, `\xNN`), bytes that are not well-formed UTF-8 become `\xNN`, and text longer than
/// `max_bytes` is cut, with a note of how much was left out. Every message that quotes input (a
/// name, a key, a value read from a file or an argument) goes through this or quote_input, and
/// InputError applies it (without the cut) to its whole message.
inline std::string printable_input(std::string_view s, std::size_t max_bytes = 80) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  std::size_t i = 0;
  while (i < s.size() && out.size() < max_bytes) {
    const auto c = static_cast<unsigned char>(s[i]);
    const std::size_t n = detail::utf8_sequence_length(s, i);
    if (c == '\n') out += "\\n";
    else if (c == '\t') out += "\\t";
    else if (c == '\r') out += "\\r";
    else if (n == 0 || c < 0x20 || c == 0x7f) out += {'\\', 'x', kHex[c >> 4], kHex[c & 15]};
    else out.append(s.substr(i, n));
    i += n == 0 ? 1 : n;
  }
  if (i < s.size()) out += "... (" + std::to_string(s.size() - i) + " more bytes)";
  return out;
}

/// printable_input between quotes: `'name'` (or `"name"` with quote = '"').
inline std::string quote_input(std::string_view s, char quote = '\'', std::size_t max_bytes = 80) {
  return quote + printable_input(s, max_bytes) + quote;
}

/// Bad input at a boundary (a file, a field, a command-line value).
/// `what()` is one line: `<source>: <field>: <reason>`; empty parts are left out, and control
/// characters or bytes that are not UTF-8 in any part are escaped (printable_input), so a file name,
/// key or value echoed from the input can never break the line. The field is cut after 200 bytes and
/// the reason after 2000.
class InputError : public std::invalid_argument {
 public:
  InputError(std::string source, std::string field, std::string reason)
      : std::invalid_argument(compose(source, field, reason)),
        source_(std::move(source)),
        field_(std::move(field)),
        reason_(std::move(reason)) {}

  const std::string& source() const noexcept { return source_; }  ///< file or stream name
  const std::string& field() const noexcept { return field_; }    ///< field path, e.g. `test[3].contract.scale`
  const std::string& reason() const noexcept { return reason_; }  ///< what is wrong

 private:
  // the source (a path, bounded by the system) is kept whole; a field path or reason built from a
  // file's keys and values is cut, so no input can make its error message unbounded
  static constexpr std::size_t kMaxFieldBytes = 200;
  static constexpr std::size_t kMaxReasonBytes = 2000;
  static std::string compose(const std::string& s, const std::string& f, const std::string& r) {
    std::string out;
    if (!s.empty()) out += printable_input(s, std::string_view::npos) + ": ";
    if (!f.empty()) out += printable_input(f, kMaxFieldBytes) + ": ";
    out += printable_input(r, kMaxReasonBytes);
    return out;
  }
  std::string source_, field_, reason_;
};

}  // namespace actionshift

/// A boundary check that is never compiled out (unlike assert): throws std::invalid_argument.
#define ACTIONSHIFT_CHECK(cond, message)                      \
  do {                                                        \
    if (!(cond)) throw std::invalid_argument(std::string(message)); \
  } while (false)
