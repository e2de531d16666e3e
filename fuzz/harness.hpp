#pragma once
// Shared by the fuzz targets: every target feeds bytes to one parser and lets only the parser's
// documented bad-input exceptions through. Anything else (a crash, a sanitizer report, a raw library
// exception such as nlohmann's out_of_range or std::bad_alloc) escapes and is a finding.

#include "actionshift/core/error.hpp"

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace actionshift::fuzz {

inline std::string_view text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Runs `parse`; InputError and std::invalid_argument (the project's bad-input errors, InputError is
/// one) are the expected outcome of hostile bytes and are swallowed, after checking the message is
/// one line.
template <class F>
void expect_input_errors(F&& parse) {
  try {
    parse();
  } catch (const std::invalid_argument& e) {
    const std::string_view what = e.what();
    if (what.find('\n') != std::string_view::npos) throw std::logic_error("multi-line error message");
  }
}

}  // namespace actionshift::fuzz
