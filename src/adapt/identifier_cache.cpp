// Where identifier weights live and the process-wide cache that loads each file once
#include "actionshift/adapt/identifier.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/weight_file.hpp"
#include "identifier_detail.hpp"

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <sstream>

namespace actionshift::adapt {
namespace {

constexpr std::uintmax_t kMaxFileBytes = detail::kMaxIdentifierFileBytes;

}  // namespace

std::string default_identifiers_dir() {
  if (const char* env = std::getenv("ACTIONSHIFT_IDENTIFIERS_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  if (std::filesystem::is_directory(ACTIONSHIFT_DEFAULT_IDENTIFIERS_DIR, ec)) return ACTIONSHIFT_DEFAULT_IDENTIFIERS_DIR;
  return ACTIONSHIFT_INSTALLED_IDENTIFIERS_DIR;
}

std::string identifier_weights_path(const std::string& weights, IdentifierKind kind, const std::string& dir) {
  if (weights.find('/') != std::string::npos || weights.ends_with(".asid")) return weights;
  return (dir.empty() ? default_identifiers_dir() : dir) + "/" + weights + "." + identifier_kind_name(kind) + ".asid";
}

std::shared_ptr<const IdentifierWeights> load_identifier_cached(const std::string& path, IdentifierKind kind) {
  static std::mutex mu;
  static std::map<std::string, std::shared_ptr<const IdentifierWeights>> cache;
  std::lock_guard<std::mutex> lock(mu);
  auto check_kind = [&](const std::shared_ptr<const IdentifierWeights>& w) {
    if (w->kind != kind)
      throw InputError(path, "header.kind", std::string("holds a ") + identifier_kind_name(w->kind) + " network, not " + identifier_kind_name(kind));
    return w;
  };
  if (auto it = cache.find(path); it != cache.end()) return check_kind(it->second);
  const std::string bytes = weight_file::read(path, kMaxFileBytes, "identifier weight file");
  // a committed file is pinned by its directory's SHA256SUMS
  const std::filesystem::path p(path);
  const std::filesystem::path sums = p.parent_path() / "SHA256SUMS";
  std::error_code ec;
  if (std::filesystem::is_regular_file(sums, ec)) {
    std::istringstream in(read_input_file(sums.string(), "a SHA256SUMS file", kMaxSmallFileBytes));
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::string hash, name;
      ls >> hash >> name;
      if (!name.empty() && name[0] == '*') name.erase(0, 1);
      if (name == p.filename().string() && hash != sha256_hex(bytes))
        throw InputError(path, "sha256", "is " + sha256_hex(bytes) + " but " + sums.string() + " lists " + hash);
    }
  }
  auto w = std::make_shared<const IdentifierWeights>(parse_identifier(bytes, path));
  cache.emplace(path, w);
  return check_kind(w);
}

}  // namespace actionshift::adapt
