#pragma once
// private helpers of the eval layer: whole-file reads, atomic writes, small checks

#include <cstdint>
#include <string>
#include <string_view>

namespace actionshift::eval::detail {

// whole file as bytes; throws InputError(path, "", reason) if it cannot be read
std::string read_file(const std::string& path);

// write `bytes` to `path` atomically: `<path>.tmp.<pid>` is written, fsynced and renamed over `path`
void atomic_write(const std::string& path, std::string_view bytes);

// true for a name made of [a-z0-9_.-] that starts with a letter or digit (tasks, splits, methods)
bool is_token(std::string_view s);

// "12.3 s" style duration for logs
std::string format_seconds(double s);

}  // namespace actionshift::eval::detail
