#pragma once
// private helpers of the eval layer: whole-file reads, small checks

#include "actionshift/core/input_file.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace actionshift::eval::detail {

// whole file as bytes, at most `max_bytes` (read_input_file: the size is checked before reading);
// throws InputError(path, "", reason) naming `what` if it cannot be read or is too large
std::string read_file(const std::string& path, const std::string& what = "an input file",
                      std::uintmax_t max_bytes = kMaxInputFileBytes);

// true for a name made of [a-z0-9_.-] that starts with a letter or digit (tasks, splits, methods)
bool is_token(std::string_view s);

// "12.3 s" style duration for logs
std::string format_seconds(double s);

}  // namespace actionshift::eval::detail
