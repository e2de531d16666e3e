#pragma once
/// \file The one way the project writes a file a reader may be looking at (results, verdicts, weights,
/// manifests, calibrations, logs, pages): the bytes go to a temporary file beside the target (named
/// with the process id, so two processes never share one), are flushed to disk, and the temporary is
/// renamed over the target. A reader sees the old file or the new one, never half of either; a failed
/// write leaves the old file and no temporary behind.

#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

namespace actionshift {

/// Writes `bytes` to `path` atomically (above). InputError(path or its temporary, "", reason) if
/// `path` exists and is not a regular file (require_replaceable_output), or the write, the fsync or
/// the rename fails; the reason carries the system's message, e.g. "x.json: write failed: No space
/// left on device".
inline void write_file_atomic(const std::string& path, std::string_view bytes) {
  require_replaceable_output(path);
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(path, "", std::string("cannot write file: ") + std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      throw InputError(path, "", std::string("write failed: ") + std::strerror(e));
    }
    done += static_cast<std::size_t>(n);
  }
  // the data must be on disk before the rename makes it visible under the final name
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw InputError(path, "", std::string("write failed: ") + std::strerror(e));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw InputError(path, "", std::string("cannot replace file: ") + std::strerror(e));
  }
}

}  // namespace actionshift
