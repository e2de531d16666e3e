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
