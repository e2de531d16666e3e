#pragma once
/// \file The checks every file reader and writer needs before it touches a path a user named: an
/// input must be a regular file (a FIFO can block forever and /dev/zero streams without end) of
/// bounded size, read by the one bounded reader read_input_file, and an output may replace only a regular file (renaming over /dev/full or a FIFO
/// would replace the device node itself).

#include "actionshift/core/error.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <string>
#include <system_error>

namespace actionshift {

/// Bounds on input files, by kind. Every reader of a file a user names goes through
/// read_input_file (or check_input_file, for a file handed to a library that opens it itself) with
/// one of these, so no input is read into memory without a size check first.
inline constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{1} << 30;      ///< results files, plans, weight and policy files: 1 GiB
inline constexpr std::uintmax_t kMaxJsonDocumentBytes = std::uintmax_t{256} << 20; ///< contract lines (file or stdin), JSON reports: 256 MiB
inline constexpr std::uintmax_t kMaxManifestBytes = std::uintmax_t{64} << 20;      ///< splits and pools (the largest built-in is 55 KB)
inline constexpr std::uintmax_t kMaxSmallFileBytes = std::uintmax_t{16} << 20;     ///< calibrations, self-test contracts, URDFs: 16 MiB
inline constexpr std::uintmax_t kMaxMeshFileBytes = std::uintmax_t{128} << 20;     ///< meshes (assimp needs several times this in memory)

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

/// The size of the regular file at `path` after checking it is one and holds at most `max_bytes`;
/// a one-line InputError naming the path otherwise (missing, special, unreadable, oversized). For a
/// file a library opens itself (a mesh read by assimp); read_input_file calls it first.
inline std::uintmax_t check_input_file(const std::string& path, const std::string& what, std::uintmax_t max_bytes) {
  if (path.empty()) throw InputError("", "", "empty path (expected " + what + ")");
  require_regular_file(path, what);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) {
    if (!std::filesystem::exists(path)) throw InputError(path, "", "no such file (expected " + what + ")");
    throw InputError(path, "", "cannot read " + what + ": " + ec.message());
  }
  if (size > max_bytes)
    throw InputError(path, "", "too large for " + what + " (" + std::to_string(size) + " bytes, at most " + std::to_string(max_bytes) + ")");
  return size;
}

namespace detail {

// reads `fd` to its end, at most `max_bytes` (InputError(source, "", …) beyond, on a read error or
// when memory runs out); `expected` (if known) reserves the string up front
inline std::string read_bounded_fd(int fd, const std::string& source, const std::string& what, std::uintmax_t max_bytes,
                                   std::uintmax_t expected) {
  std::string bytes;
  try {
    if (expected > 0) bytes.reserve(static_cast<std::size_t>(expected));
    char buf[1 << 16];
    for (;;) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw InputError(source, "", "read error (" + what + "): " + std::strerror(errno));
      if (n == 0) break;
      if (bytes.size() + static_cast<std::size_t>(n) > max_bytes)
        throw InputError(source, "", "too large for " + what + " (more than " + std::to_string(max_bytes) + " bytes)");
      bytes.append(buf, static_cast<std::size_t>(n));
    }
  } catch (const std::bad_alloc&) {
    throw InputError(source, "", "out of memory reading " + what + " (" + std::to_string(bytes.size()) + " bytes read)");
  }
  return bytes;
}

struct FdCloser {
  int fd;
  ~FdCloser() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace detail

/// The whole regular file at `path`, at most `max_bytes`: the one bounded reader of every input
/// file. The size is checked before anything is read; a missing, unreadable, special or oversized
/// file, a read error, running out of memory, or a file that reads shorter than its size (cut while
/// being read) is a one-line InputError naming the path and `what` (the kind of file).
inline std::string read_input_file(const std::string& path, const std::string& what,
                                   std::uintmax_t max_bytes = kMaxInputFileBytes) {
  const std::uintmax_t size = check_input_file(path, what, max_bytes);
  const detail::FdCloser f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (f.fd < 0) throw InputError(path, "", "cannot open " + what + ": " + std::strerror(errno));
  struct stat st{};
  if (::fstat(f.fd, &st) != 0 || !S_ISREG(st.st_mode))  // replaced between the check and the open
    throw InputError(path, "", "not a regular file (expected " + what + ")");
  std::string bytes = detail::read_bounded_fd(f.fd, path, what, max_bytes, size);
  if (bytes.size() < size)
    throw InputError(path, "", "short read (" + std::to_string(bytes.size()) + " of " + std::to_string(size) + " bytes of " + what +
                                   "; was the file cut while being read?)");
  return bytes;
}

/// Standard input to its end, at most `max_bytes` (a regular file redirected to it is refused by its
/// size before reading, as read_input_file does). `source` names it in errors ("<stdin>").
inline std::string read_input_stdin(const std::string& source, const std::string& what, std::uintmax_t max_bytes) {
  struct stat st{};
  std::uintmax_t expected = 0;
  if (::fstat(STDIN_FILENO, &st) == 0 && S_ISREG(st.st_mode)) {
    const auto pos = ::lseek(STDIN_FILENO, 0, SEEK_CUR);
    const auto size = static_cast<std::uintmax_t>(st.st_size);
    const auto start = pos > 0 ? static_cast<std::uintmax_t>(pos) : 0;
    expected = size > start ? size - start : 0;
    if (expected > max_bytes)
      throw InputError(source, "", "too large for " + what + " (" + std::to_string(expected) + " bytes, at most " + std::to_string(max_bytes) + ")");
  }
  return detail::read_bounded_fd(STDIN_FILENO, source, what, max_bytes, expected);
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
