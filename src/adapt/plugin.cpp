#include "actionshift/adapt/plugin.hpp"

#include "actionshift/adapt/identifier.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/input_file.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <mutex>
#include <shared_mutex>

namespace actionshift::adapt {

namespace {

struct Entry {
  std::shared_ptr<const MethodPlugin> plugin;
  std::string kind;
  std::vector<std::string> files;  // absolute
};

struct Registry {
  std::shared_mutex mutex;
  std::map<std::string, Entry, std::less<>> entries;
};

Registry& registry() {
  static Registry r;
  return r;
}

bool is_builtin(std::string_view name) {
  const auto& n = method_names();
  return std::find(n.begin(), n.end(), name) != n.end() || parse_identifier_kind(std::string(name)).has_value();
}

bool is_name(std::string_view s) {
  if (s.empty() || s.size() > 64 || !(s[0] >= 'a' && s[0] <= 'z')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-'; });
}

std::string files_sha256(const std::vector<std::string>& files, const std::string& source) {
  if (files.empty()) return "";
  std::vector<std::string> hashes;
  for (const auto& f : files) {
    try {
      hashes.push_back(sha256_hex(read_input_file(f, "method file")));
    } catch (const InputError& e) {
      throw InputError(f, source + ".files", e.reason());
    }
  }
  std::sort(hashes.begin(), hashes.end());
  return sha256_hex(canonical_dump(nlohmann::json(hashes)));
}

}  // namespace

std::string_view rung_name(Rung rung) noexcept {
  switch (rung) {
    case Rung::oracle: return "oracle";
    case Rung::pool: return "pool";
    case Rung::grammar: return "grammar";
    case Rung::none: return "none";
  }
  return "none";
}

Rung parse_rung(std::string_view text, const std::string& source, const std::string& field) {
  for (Rung r : {Rung::oracle, Rung::pool, Rung::grammar, Rung::none})
    if (text == rung_name(r)) return r;
  throw InputError(source, field, "expected pool, grammar or none (got " + quote_input(text, '"') + ")");
}

Rung method_rung(const std::string& method) {
  if (auto p = find_method_plugin(method)) return p->rung;
  if (method == "oracle" || method == "delayed_oracle") return Rung::oracle;
  if (method == "grammar_belief") return Rung::grammar;
  if (method == "no_adapt" || parse_identifier_kind(method)) return Rung::none;
  (void)resolve_method_params(method);  // unknown names throw
  return Rung::pool;
}

const GrammarGrids& grammar_grids() {
  static const GrammarGrids g{{grammar::kScaleGrid.begin(), grammar::kScaleGrid.end()},
                              {grammar::kLagGrid.begin(), grammar::kLagGrid.end()},
                              {"delta", "absolute"},
                              {"base", "tool"},
                              true,
                              true,
                              true};
  return g;
}

MethodRegistration& MethodRegistration::operator=(MethodRegistration&& o) noexcept {
  if (this != &o) {
    MethodRegistration old(std::move(*this));
    name_ = std::exchange(o.name_, {});
  }
  return *this;
}

MethodRegistration::~MethodRegistration() {
  if (name_.empty()) return;
  Registry& r = registry();
  std::unique_lock lock(r.mutex);
  r.entries.erase(name_);
}

MethodRegistration register_method(MethodPlugin plugin, const std::string& kind) {
  const std::string src = "method " + printable_input(plugin.name);
  const bool external_name = kind == "external" && plugin.name.starts_with("external:") && plugin.name.size() > 9 &&
                             plugin.name.size() <= 4096 &&
                             std::none_of(plugin.name.begin(), plugin.name.end(), [](char c) {
                               return c == '{' || c == '}' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
                             });
  if (!is_name(plugin.name) && !external_name)
    throw InputError(src, "name", "expected a name of [a-z0-9_.-] starting with a letter, at most 64 characters");
  if (is_builtin(plugin.name)) throw InputError(src, "name", "is a built-in method's name; choose another");
  if (plugin.version.empty() || plugin.version.size() > 64 ||
      !std::all_of(plugin.version.begin(), plugin.version.end(), [](char c) { return c > ' ' && c < 127; }))
    throw InputError(src, "version", "expected 1 to 64 printable characters without spaces (got " + quote_input(plugin.version, '"') + ")");
  if (plugin.rung == Rung::oracle)
    throw InputError(src, "rung", "the oracle rung is reserved for the built-in oracle (declare pool, grammar or none)");
  if (!plugin.factory) throw InputError(src, "factory", "is empty");
  if (!plugin.code_sha256.empty() && !is_sha256_hex(plugin.code_sha256))
    throw InputError(src, "code_sha256", "expected 64 lowercase hex digits");
  if (!plugin.params.is_object()) throw InputError(src, "params", "expected a JSON object of parameters and their defaults");
  try {
    (void)canonical_dump(plugin.params);
  } catch (const std::invalid_argument& e) {
    throw InputError(src, "params", e.what());
  }
  if (kind != "cpp" && kind != "python" && kind != "external") throw InputError(src, "kind", "expected cpp, python or external");
  Entry e;
  for (const auto& f : plugin.files) {
    std::error_code ec;
    const auto abs = std::filesystem::absolute(f, ec);
    e.files.push_back(ec ? f : abs.lexically_normal().string());
  }
  (void)files_sha256(e.files, src);  // an unreadable file fails now, not in the first episode
  e.kind = kind;
  const std::string name = plugin.name;
  e.plugin = std::make_shared<const MethodPlugin>(std::move(plugin));
  Registry& r = registry();
  std::unique_lock lock(r.mutex);
  if (!r.entries.emplace(name, std::move(e)).second) throw InputError(src, "name", "is already registered");
  return MethodRegistration(name);
}

std::shared_ptr<const MethodPlugin> find_method_plugin(std::string_view name) {
  Registry& r = registry();
  std::shared_lock lock(r.mutex);
  const auto it = r.entries.find(name);
  return it == r.entries.end() ? nullptr : it->second.plugin;
}

std::vector<std::string> method_plugin_names() {
  Registry& r = registry();
  std::shared_lock lock(r.mutex);
  std::vector<std::string> out;
  for (const auto& [name, e] : r.entries) out.push_back(name);
  return out;
}

std::optional<PluginIdentity> method_plugin_identity(std::string_view name) {
  Entry e;
  {
    Registry& r = registry();
    std::shared_lock lock(r.mutex);
    const auto it = r.entries.find(name);
    if (it == r.entries.end()) return std::nullopt;
    e = it->second;
  }
  PluginIdentity id;
  id.kind = e.kind;
  id.version = e.plugin->version;
  id.rung = std::string(rung_name(e.plugin->rung));
  id.files = e.files;
  const nlohmann::json content = {{"code_sha256", e.plugin->code_sha256},
                                  {"files_sha256", files_sha256(e.files, "method " + e.plugin->name)},
                                  {"kind", e.kind},
                                  {"name", e.plugin->name},
                                  {"rung", id.rung},
                                  {"version", id.version}};
  id.sha256 = sha256_hex(canonical_dump(content));
  return id;
}

}  // namespace actionshift::adapt
