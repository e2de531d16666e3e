#include "io.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace actionshift::eval::detail {

std::string read_file(const std::string& path, const std::string& what, std::uintmax_t max_bytes) {
  return read_input_file(path, what, max_bytes);
}

void atomic_write(const std::string& path, std::string_view bytes) {
  require_replaceable_output(path);
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(tmp, "", std::string("cannot create file: ") + std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      throw InputError(tmp, "", std::string("write failed: ") + std::strerror(e));
    }
    done += static_cast<std::size_t>(n);
  }
  // the data must be on disk before the rename makes it visible under the final name
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw InputError(tmp, "", std::string("fsync/close failed: ") + std::strerror(e));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw InputError(path, "", std::string("rename failed: ") + std::strerror(e));
  }
}

bool is_token(std::string_view s) {
  if (s.empty() || s.size() > 128) return false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool alnum = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
    if (i == 0 && !alnum) return false;
    if (!alnum && c != '_' && c != '-' && c != '.') return false;
  }
  return true;
}

std::string format_seconds(double s) {
  char buf[64];
  if (!(s >= 0.0) || s > 1e9) return "--";
  const auto total = static_cast<long long>(s + 0.5);
  if (total < 60) std::snprintf(buf, sizeof buf, "%llds", total);
  else if (total < 3600) std::snprintf(buf, sizeof buf, "%lldm%02llds", total / 60, total % 60);
  else std::snprintf(buf, sizeof buf, "%lldh%02lldm", total / 3600, (total % 3600) / 60);
  return buf;
}

}  // namespace actionshift::eval::detail
