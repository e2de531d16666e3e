// validate, contract hash/decode/encode, splits generate.
#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/splits.hpp"
#include "actionshift/core/transforms.hpp"
#include "actionshift/core/validate.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "cmd_eval.hpp"
#include "commands.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

namespace actionshift::cli {
namespace fs = std::filesystem;

namespace {

std::string read_file(const std::string& path) { return read_input_file(path, "a contract input file", kMaxJsonDocumentBytes); }

// input lines: an inline JSON argument, a file, or stdin
std::vector<std::pair<std::string, std::string>> input_lines(const std::string& input) {
  std::string text, source;
  if (input.empty() || input == "-") {
    source = "<stdin>";
    text = read_input_stdin(source, "contract input", kMaxJsonDocumentBytes);
  } else if (!input.empty() && (input.front() == '{' || input.front() == '[')) {
    text = input;
    source = "<argument>";
  } else {
    text = read_file(input);
    source = input;
  }
  std::vector<std::pair<std::string, std::string>> lines;
  std::stringstream ss(text);
  std::string line;
  int n = 0;
  while (std::getline(ss, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    lines.emplace_back(source + ":" + std::to_string(n), line);
  }
  if (lines.empty()) throw InputError(source, "", "no input (expected one JSON object per line)");
  return lines;
}

nlohmann::json parse_object(const std::string& where, const std::string& line) {
  const nlohmann::json j = parse_json_input(line, where);
  if (!j.is_object()) throw InputError(where, "", "expected a JSON object");
  return j;
}

Contract contract_field(const std::string& where, const nlohmann::json& j) {
  if (!j.contains("contract")) throw InputError(where, "contract", "missing field");
  try {
    return Contract::from_json_value(j["contract"]);
  } catch (const std::invalid_argument& e) {
    throw InputError(where, "contract", e.what());
  }
}

template <int N>
Eigen::Matrix<double, N, 1> vec_field(const std::string& where, const nlohmann::json& v, const std::string& field) {
  if (!v.is_array() || v.size() != static_cast<std::size_t>(N))
    throw InputError(where, field, "must be a list of " + std::to_string(N) + " numbers");
  Eigen::Matrix<double, N, 1> out;
  for (int i = 0; i < N; ++i) {
    const auto& x = v[static_cast<std::size_t>(i)];
    if (!x.is_number()) throw InputError(where, field, "must be a list of " + std::to_string(N) + " numbers");
    out[i] = x.get<double>();
    if (!std::isfinite(out[i])) throw InputError(where, field, "must be finite");
  }
  return out;
}

Mat3 rotation_field(const std::string& where, const nlohmann::json& j) {
  if (j.contains("rotation") && j.contains("quat_wxyz")) throw InputError(where, "rotation", "give rotation or quat_wxyz, not both");
  Mat3 R = Mat3::Identity();
  if (j.contains("quat_wxyz")) {
    const auto q = vec_field<4>(where, j["quat_wxyz"], "quat_wxyz");
    // a zero quaternion (or one whose norm overflows or underflows) would silently decode as identity
    const double n = q.norm();
    if (!(n > 1e-9) || !std::isfinite(n))
      throw InputError(where, "quat_wxyz", "must be a non-zero quaternion of finite, representable norm (w x y z)");
    R = quat_wxyz_to_matrix(q);
  } else if (j.contains("rotation")) {
    const auto& r = j["rotation"];
    if (!r.is_array() || r.size() != 3) throw InputError(where, "rotation", "must be a 3x3 list of rows");
    for (int i = 0; i < 3; ++i) R.row(i) = vec_field<3>(where, r[static_cast<std::size_t>(i)], "rotation").transpose();
  }
  std::string why;
  if (!is_rotation(R, &why)) throw InputError(where, "rotation", why);
  return R;
}

template <class V>
nlohmann::json to_list(const V& v) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

void check_keys(const std::string& where, const nlohmann::json& j, std::initializer_list<const char*> allowed) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool ok = false;
    for (const char* a : allowed) ok = ok || it.key() == a;
    if (!ok) throw InputError(where, it.key(), "unknown field");
  }
}

// all *.json under the given paths, in a stable order
std::vector<std::string> manifest_files(const std::vector<std::string>& paths) {
  std::vector<std::string> files;
  for (const auto& p : paths) {
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<std::string> found;
      fs::directory_iterator it(p, ec), end;
      if (ec) throw InputError(p, "", "cannot list directory: " + ec.message());
      for (; it != end; it.increment(ec)) {
        std::error_code type_ec;
        if (it->is_regular_file(type_ec) && it->path().extension() == ".json") found.push_back(it->path().string());
      }
      if (ec) throw InputError(p, "", "cannot list directory: " + ec.message());
      std::sort(found.begin(), found.end());
      if (found.empty()) throw InputError(p, "", "directory holds no *.json manifest");
      files.insert(files.end(), found.begin(), found.end());
    } else if (fs::exists(p, ec)) {
      files.push_back(p);
    } else {
      throw InputError(p, "", "no such file or directory");
    }
  }
  return files;
}

std::string pad(std::string s, std::size_t w) {
  if (s.size() < w) s.append(w - s.size(), ' ');
  return s;
}

}  // namespace

int run_validate(const ValidateOptions& o) {
  // load everything first: a malformed file is bad input (exit 2), named with its field
  std::vector<std::pair<std::string, Manifest>> loaded;
  if (o.paths.empty()) {
    for (const auto& name : data::builtin_manifest_names())
      loaded.emplace_back("builtin:" + name, data::resolve_manifest(name));
    if (loaded.empty()) throw InputError("validate", "", "this build has no built-in manifests; pass a directory");
  } else {
    for (const auto& f : manifest_files(o.paths)) loaded.emplace_back(f, Manifest::load(f));
  }

  int failed = 0;
  nlohmann::json report = nlohmann::json::array();
  std::map<std::string, Manifest> by_name;
  for (const auto& [source, m] : loaded) {
    const std::string stem = source.rfind("builtin:", 0) == 0 ? source.substr(8) : fs::path(source).stem().string();
    std::vector<Check> checks = validate(m);
    // a manifest's identity is its content hash and its name a label: a file of another name (a copy,
    // a generated split renamed) is valid, and only noted
    checks.insert(checks.begin(), Check{"name", true,
                                        m.name() == stem ? m.name()
                                                         : m.name() + " (file name '" + stem +
                                                               "': the name is a label, the content hash the identity)"});
    nlohmann::json jr = {{"file", source}, {"checks", nlohmann::json::array()}};
    for (const auto& c : checks) {
      failed += c.ok ? 0 : 1;
      jr["checks"].push_back({{"check", c.name}, {"ok", c.ok}, {"detail", c.detail}});
      if (!o.json && (!c.ok || !o.quiet))
        std::cout << (c.ok ? "ok   " : "FAIL ") << source << ": " << c.name << ": " << c.detail << "\n";
    }
    report.push_back(jr);
    by_name.emplace(m.name(), m);
  }
  for (const auto& c : validate_set(by_name)) {
    failed += c.ok ? 0 : 1;
    report.push_back({{"file", "(set)"}, {"checks", {{{"check", c.name}, {"ok", c.ok}, {"detail", c.detail}}}}});
    if (!o.json && (!c.ok || !o.quiet)) std::cout << (c.ok ? "ok   " : "FAIL ") << "(set): " << c.name << ": " << c.detail << "\n";
  }

  if (o.json) {
    nlohmann::json summary = nlohmann::json::array();
    for (const auto& [name, m] : by_name)
      summary.push_back({{"name", name}, {"kind", m.is_pool() ? "pool" : "split"}, {"rule", m.rule()}, {"seed", m.seed()},
                         {"train", m.train().size()}, {"contracts", m.test().size()}, {"manifest_sha256", m.manifest_sha256()},
                         {"pool_sha256", m.is_pool() ? nlohmann::json(m.pool_sha256()) : nlohmann::json(nullptr)}});
    std::cout << nlohmann::json({{"ok", failed == 0}, {"failed_checks", failed}, {"files", report}, {"manifests", summary}}).dump(2) << "\n";
    return failed ? kCheckFailed : kOk;
  }

  std::cout << "\n" << pad("manifest", 30) << pad("kind", 7) << pad("train", 7) << pad("eval", 6) << pad("signatures (eval)", 19)
            << pad("lags", 10) << "hash\n";
  for (const auto& [name, m] : by_name) {
    std::set<std::vector<std::string>> sigs;
    std::set<int> lags;
    for (const auto& r : m.test()) {
      sigs.insert(r.contract.composition_signature());
      lags.insert(r.contract.lag());
    }
    std::string lag_s;
    for (int l : lags) {
      if (!lag_s.empty()) lag_s += ',';
      lag_s += std::to_string(l);
    }
    std::cout << pad(name, 30) << pad(m.is_pool() ? "pool" : "split", 7) << pad(std::to_string(m.train().size()), 7)
              << pad(std::to_string(m.test().size()), 6) << pad(std::to_string(sigs.size()), 19) << pad(lag_s, 10)
              << "manifest " << m.manifest_sha256().substr(0, 16) << "\n";
    if (m.is_pool()) std::cout << pad("", 30) << "pool_sha256 " << m.pool_sha256() << "\n";
  }
  std::cout << "\n";
  if (failed) std::cout << failed << " check(s) FAILED";
  else std::cout << "all checks passed";
  std::cout << " over " << counted(loaded.size(), "manifest") << "\n";
  return failed ? kCheckFailed : kOk;
}

int run_contract_hash(const ContractOptions& o) {
  for (const auto& [where, line] : input_lines(o.input)) {
    const nlohmann::json j = parse_object(where, line);
    // accept a bare contract or {"contract": {...}}
    Contract c;
    try {
      c = Contract::from_json_value(j.contains("contract") && j.size() == 1 ? j["contract"] : j);
    } catch (const std::invalid_argument& e) {
      throw InputError(where, "contract", e.what());
    }
    std::cout << canonical_dump({{"sha256", c.sha256()}, {"canonical", c.to_json()}, {"composition", c.composition_signature()}}) << "\n";
  }
  return kOk;
}

int run_contract_decode(const ContractOptions& o) {
  for (const auto& [where, line] : input_lines(o.input)) {
    const nlohmann::json j = parse_object(where, line);
    check_keys(where, j, {"contract", "raw", "rotation", "quat_wxyz", "tracked_target"});
    const Contract c = contract_field(where, j);
    const Mat3 R = rotation_field(where, j);
    if (!j.contains("raw")) throw InputError(where, "raw", "missing field");
    const auto& raw = j["raw"];
    if (raw.is_array() && !raw.empty() && raw[0].is_array()) {
      // a sequence: stateful decoding (tracked target from zero, lag FIFO)
      if (j.contains("tracked_target")) throw InputError(where, "tracked_target", "not allowed with a raw sequence (the decoder tracks it from zero)");
      Decoder d(c);
      nlohmann::json out = nlohmann::json::array();
      for (std::size_t t = 0; t < raw.size(); ++t)
        out.push_back(to_list(d.step(vec_field<7>(where, raw[t], "raw[" + std::to_string(t) + "]"), R)));
      std::cout << canonical_dump({{"canonical", out}, {"final_target", to_list(d.tracked_target())}}) << "\n";
    } else {
      const Pose6 T = j.contains("tracked_target") ? vec_field<6>(where, j["tracked_target"], "tracked_target") : Pose6::Zero();
      Pose6 next;
      const Action canonical = decode(c, vec_field<7>(where, raw, "raw"), R, T, &next);
      std::cout << canonical_dump({{"canonical", to_list(canonical)}, {"next_target", to_list(next)}}) << "\n";
    }
  }
  return kOk;
}

int run_contract_encode(const ContractOptions& o) {
  for (const auto& [where, line] : input_lines(o.input)) {
    const nlohmann::json j = parse_object(where, line);
    check_keys(where, j, {"contract", "canonical", "rotation", "quat_wxyz", "tracked_target"});
    const Contract c = contract_field(where, j);
    const Mat3 R = rotation_field(where, j);
    if (!j.contains("canonical")) throw InputError(where, "canonical", "missing field");
    const Pose6 T = j.contains("tracked_target") ? vec_field<6>(where, j["tracked_target"], "tracked_target") : Pose6::Zero();
    const Action raw = encode(c, vec_field<7>(where, j["canonical"], "canonical"), R, T);
    std::cout << canonical_dump({{"raw", to_list(raw)}}) << "\n";
  }
  return kOk;
}

int run_splits_generate(const SplitsGenerateOptions& o) {
  const auto all = splits::all_rules();
  const std::vector<std::string> rules = o.rules.empty() ? all : o.rules;
  for (const auto& r : rules)
    if (std::find(all.begin(), all.end(), r) == all.end()) throw InputError("--rule", r, "unknown split rule");
  check_output_dir(o.out_dir, "--out");
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec) throw InputError(o.out_dir, "--out", "cannot create directory: " + ec.message());
  for (const auto& r : rules) {
    const Manifest m = splits::generate(r, o.seed);
    const fs::path path = fs::path(o.out_dir) / (r + ".json");
    write_file_atomic(path.string(), m.serialize());  // a directory, FIFO or device of that name is not replaced
    std::cout << path.string() << "  " << (m.is_pool() ? "pool " : "split ") << m.test().size() << " contracts  manifest_sha256 "
              << m.manifest_sha256() << "\n";
  }
  return kOk;
}

}  // namespace actionshift::cli
