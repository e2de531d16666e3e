#pragma once
/// \file The checks every file reader and writer needs before it touches a path a user named: an
/// input must be a regular file (a FIFO can block forever and /dev/zero streams without end) of
/// bounded size, and an output may replace only a regular file (renaming over /dev/full or a FIFO
/// would replace the device node itself).

#include "actionshift/core/error.hpp"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>

namespace actionshift {

/// Default bound on an input file's size (results files, plans, manifests, weight files).
inline constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{1} << 30;  // 1 GiB

/// InputError(path, "", …) if `path` exists and is not a regular file (following symlinks). A
/// missing path passes: the caller's own open reports it.
inline void require_regular_file(const std::string& path, const std::string& what) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st)) return;
  if (std::filesystem::is_directory(st)) throw InputError(path, "", "is a directory, not a file (expected " + what + ")");
  if (!std::filesystem::is_regular_file(st))
    throw InputError(path, "", "not a regular file (a device, FIFO or socket; expected " + what + ")");
}

/// The whole regular file at `path`, at most `max_bytes`; a one-line InputError naming the path for
/// a missing, unreadable, special or oversized file.
inline std::string read_input_file(const std::string& path, const std::string& what,
                                   std::uintmax_t max_bytes = kMaxInputFileBytes) {
  require_regular_file(path, what);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > max_bytes)
    throw InputError(path, "", what + " too large (" + std::to_string(size) + " bytes, at most " + std::to_string(max_bytes) + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open " + what);
  std::string bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>{});
  if (in.bad()) throw InputError(path, "", "read error");
  if (bytes.size() > max_bytes) throw InputError(path, "", what + " too large (grew while being read)");
  return bytes;
}

/// InputError(path, "", …) if `path` exists and is not a regular file: an output written through a
/// temporary file and a rename must not replace a device node, FIFO or directory.
inline void require_replaceable_output(const std::string& path) {
  std::error_code ec;
  const auto st = std::filesystem::symlink_status(path, ec);
  if (ec || !std::filesystem::exists(st)) return;
  if (std::filesystem::is_symlink(st)) {
    const auto target = std::filesystem::status(path, ec);
    if (!ec && std::filesystem::exists(target) && !std::filesystem::is_regular_file(target))
      throw InputError(path, "", "exists and is not a regular file (refusing to replace it)");
    return;
  }
  if (!std::filesystem::is_regular_file(st)) throw InputError(path, "", "exists and is not a regular file (refusing to replace it)");
}

/// InputError(path, "", …) unless `path` can be written later: its directory exists and is a
/// directory, and the path itself is absent or a regular file. Commands that work for minutes (a
/// training run, a gate) check this first, so a typo in --out does not cost the run.
inline void require_writable_output(const std::string& path) {
  require_replaceable_output(path);
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
    throw InputError(path, "", "cannot write here: " + parent.string() + " is not a directory");
}

}  // namespace actionshift
