#pragma once
/// \file The action contract: an immutable value type describing how a hidden interface re-maps
/// raw action numbers before the controller sees them (docs/semantics.md §2; docs/reference.md, *Contracts*).
///
/// Fields (names are part of the JSON and hash format): `permutation` (output channel i reads raw
/// channel permutation[i]), `sign` and `scale` (indexed by OUTPUT channel), `target` (delta or
/// absolute), `frame` (base or tool), `lag` (whole-action delay in control steps) and
/// `gripper_inverted`. Hashes equal the reference's: sha256 of the canonical JSON.

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/types.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift {

enum class Target { kDelta, kAbsolute };  ///< delta: command is an increment; absolute: a new target
enum class Frame { kBase, kTool };        ///< frame the pose command is expressed in

inline constexpr int kMaxLag = 1024;  ///< our bound (the reference has none): keeps the FIFO finite

inline const char* to_string(Target t) { return t == Target::kDelta ? "delta" : "absolute"; }
inline const char* to_string(Frame f) { return f == Frame::kBase ? "base" : "tool"; }

/// Unvalidated contract fields, as read from JSON or written by a generator.
/// Vectors allow the validator to report the reference's dimension errors.
struct ContractFields {
  std::vector<long long> permutation{0, 1, 2, 3, 4, 5};
  std::vector<long long> sign{1, 1, 1, 1, 1, 1};
  std::vector<double> scale{1.0, 1.0, 1.0, 1.0, 1.0, 1.0};
  std::string target{"delta"};
  std::string frame{"base"};
  long long lag{0};
  bool gripper_inverted{false};
};

class Contract {
 public:
  /// The identity contract (no re-mapping): hash 6b38e10f…1eaa.
  Contract() = default;
  static Contract identity() { return Contract(); }

  /// Validates `f` and builds a contract. Throws std::invalid_argument with the reference's
  /// message for the first violated rule (order as the reference implementation's, docs/reference.md *Contracts*, plus our D == 6 and lag bound).
  static Contract make(const ContractFields& f) {
    std::string err;
    auto c = try_make(f, &err);
    if (!c) throw std::invalid_argument(err);
    return *c;
  }

  /// Non-throwing twin of make(): returns nullopt and fills `*err` (if given).
  static std::optional<Contract> try_make(const ContractFields& f, std::string* err) noexcept {
    auto fail = [&](const char* msg) -> std::optional<Contract> {
      if (err) *err = msg;
      return std::nullopt;
    };
    const std::size_t d = f.permutation.size();
    if (d == 0) return fail("contract must have at least one pose component");
    if (f.sign.size() != d || f.scale.size() != d) return fail("contract component dimensions must match");
    if (d != static_cast<std::size_t>(kPoseDim))
      return fail("contract must have 6 pose components (dx, dy, dz, rx, ry, rz)");
    std::array<long long, kPoseDim> sorted{};
    std::copy(f.permutation.begin(), f.permutation.end(), sorted.begin());
    std::sort(sorted.begin(), sorted.end());
    for (int i = 0; i < kPoseDim; ++i)
      if (sorted[static_cast<std::size_t>(i)] != i) return fail("permutation must be a bijection over component indices");
    for (long long s : f.sign)
      if (s != -1 && s != 1) return fail("sign values must be -1 or 1");
    for (double s : f.scale)
      if (!std::isfinite(s) || s <= 0.0) return fail("scale values must be finite and positive");
    if (f.lag < 0) return fail("lag must be nonnegative");
    if (f.lag > kMaxLag) return fail("lag must be at most 1024 control steps");
    Contract c;
    if (f.target == "delta") c.target_ = Target::kDelta;
    else if (f.target == "absolute") c.target_ = Target::kAbsolute;
    else return fail("target must be 'delta' or 'absolute'");
    if (f.frame == "base") c.frame_ = Frame::kBase;
    else if (f.frame == "tool") c.frame_ = Frame::kTool;
    else return fail("frame must be 'base' or 'tool'");
    for (int i = 0; i < kPoseDim; ++i) {
      const auto k = static_cast<std::size_t>(i);
      c.perm_[k] = static_cast<int>(f.permutation[k]);
      c.sign_[k] = static_cast<int>(f.sign[k]);
      c.scale_[k] = f.scale[k];
      c.gain_[k] = c.sign_[k] * c.scale_[k];
    }
    c.lag_ = static_cast<int>(f.lag);
    c.gripper_inverted_ = f.gripper_inverted;
    return c;
  }

  /// Parses the reference's JSON object form. Rejects unknown and missing fields
  /// ("unknown contract fields: a, b" / "missing contract fields: …"), a non-integer or boolean
  /// lag ("lag must be an integer"), a non-boolean gripper_inverted, then validates as make().
  static Contract from_json_value(const nlohmann::json& j) {
    if (!j.is_object()) throw std::invalid_argument("contract must be a JSON object");
    static const std::array<std::string, 7> kKeys{"frame", "gripper_inverted", "lag", "permutation",
                                                  "scale", "sign", "target"};
    std::vector<std::string> unknown, missing;
    for (auto it = j.begin(); it != j.end(); ++it)
      if (std::find(kKeys.begin(), kKeys.end(), it.key()) == kKeys.end()) unknown.push_back(it.key());
    for (const auto& k : kKeys)
      if (!j.contains(k)) missing.push_back(k);
    auto join = [](const std::vector<std::string>& v) {  // keys come from the input: escaped and cut
      std::string s;
      for (std::size_t i = 0; i < v.size() && i < 8; ++i) s += (s.empty() ? "" : ", ") + printable_input(v[i], 40);
      if (v.size() > 8) s += ", ... (" + std::to_string(v.size() - 8) + " more)";
      return s;
    };
    if (!unknown.empty()) throw std::invalid_argument("unknown contract fields: " + join(unknown));
    if (!missing.empty()) throw std::invalid_argument("missing contract fields: " + join(missing));

    ContractFields f;
    f.permutation = int_list(j["permutation"], "permutation");
    f.sign = int_list(j["sign"], "sign");
    const auto& sc = j["scale"];
    if (!sc.is_array()) throw std::invalid_argument("scale must be a list of numbers");
    f.scale.clear();
    for (const auto& v : sc) {
      if (!v.is_number()) throw std::invalid_argument("scale must be a list of numbers");
      f.scale.push_back(v.get<double>());
    }
    const auto& lag = j["lag"];
    if (!lag.is_number_integer()) throw std::invalid_argument("lag must be an integer");
    f.lag = lag.is_number_unsigned() && lag.get<unsigned long long>() > static_cast<unsigned long long>(kMaxLag)
                ? kMaxLag + 1
                : lag.get<long long>();
    if (!j["target"].is_string()) throw std::invalid_argument("target must be 'delta' or 'absolute'");
    f.target = j["target"].get<std::string>();
    if (!j["frame"].is_string()) throw std::invalid_argument("frame must be 'base' or 'tool'");
    f.frame = j["frame"].get<std::string>();
    if (!j["gripper_inverted"].is_boolean()) throw std::invalid_argument("gripper_inverted must be boolean");
    f.gripper_inverted = j["gripper_inverted"].get<bool>();
    return make(f);
  }

  /// Parses JSON text; a syntax error, nesting deeper than kMaxJsonDepth or a number outside a
  /// double's range becomes an InputError (a std::invalid_argument) "contract: <field>: <reason>".
  static Contract from_json(std::string_view text) {
    return from_json_value(parse_json_input(text, "contract"));
  }

  /// The JSON object form (keys sorted by nlohmann's std::map).
  nlohmann::json to_json_value() const {
    nlohmann::json j;
    j["frame"] = to_string(frame_);
    j["gripper_inverted"] = gripper_inverted_;
    j["lag"] = lag_;
    j["permutation"] = perm_;
    j["scale"] = scale_;
    j["sign"] = sign_;
    j["target"] = to_string(target_);
    return j;
  }

  /// Canonical JSON, byte-compatible with the reference's `to_json` (sorted, compact, repr floats).
  std::string to_json() const { return canonical_dump(to_json_value()); }
  /// Lowercase hex sha256 of to_json(): the contract's identity everywhere in ActionShift.
  std::string sha256() const { return sha256_hex(to_json()); }

  /// Field names that differ from identity, in the fixed order permutation, sign, scale, target,
  /// frame, lag, gripper (note: "gripper", not "gripper_inverted"; docs/reference.md, Contracts).
  std::vector<std::string> composition_signature() const {
    std::vector<std::string> s;
    const Contract id;
    if (perm_ != id.perm_) s.emplace_back("permutation");
    if (sign_ != id.sign_) s.emplace_back("sign");
    if (scale_ != id.scale_) s.emplace_back("scale");
    if (target_ != Target::kDelta) s.emplace_back("target");
    if (frame_ != Frame::kBase) s.emplace_back("frame");
    if (lag_ != 0) s.emplace_back("lag");
    if (gripper_inverted_) s.emplace_back("gripper");
    return s;
  }

  /// Back to editable fields (for derived contracts: `auto f = c.fields(); f.lag = 2;`).
  ContractFields fields() const {
    ContractFields f;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto k = static_cast<std::size_t>(i);
      f.permutation[k] = perm_[k];
      f.sign[k] = sign_[k];
      f.scale[k] = scale_[k];
    }
    f.target = to_string(target_);
    f.frame = to_string(frame_);
    f.lag = lag_;
    f.gripper_inverted = gripper_inverted_;
    return f;
  }

  const std::array<int, kPoseDim>& permutation() const noexcept { return perm_; }  ///< output i reads raw perm[i]
  const std::array<int, kPoseDim>& sign() const noexcept { return sign_; }         ///< per output channel, ±1
  const std::array<double, kPoseDim>& scale() const noexcept { return scale_; }    ///< per output channel, > 0
  /// sign[i]·scale[i]: the factor applied to output channel i.
  const std::array<double, kPoseDim>& gain() const noexcept { return gain_; }
  Target target() const noexcept { return target_; }
  Frame frame() const noexcept { return frame_; }
  int lag() const noexcept { return lag_; }  ///< control steps, in [0, kMaxLag]
  bool gripper_inverted() const noexcept { return gripper_inverted_; }

  bool operator==(const Contract& o) const noexcept {
    return perm_ == o.perm_ && sign_ == o.sign_ && scale_ == o.scale_ && target_ == o.target_ &&
           frame_ == o.frame_ && lag_ == o.lag_ && gripper_inverted_ == o.gripper_inverted_;
  }

 private:
  static std::vector<long long> int_list(const nlohmann::json& v, const char* name) {
    const std::string msg = std::string(name) + " must be a list of integers";
    if (!v.is_array()) throw std::invalid_argument(msg);
    std::vector<long long> out;
    for (const auto& x : v) {
      if (!x.is_number_integer()) throw std::invalid_argument(msg);
      if (x.is_number_unsigned() && x.get<unsigned long long>() > 1000000ULL) out.push_back(1000000);
      else out.push_back(x.get<long long>());
    }
    return out;
  }

  std::array<int, kPoseDim> perm_{0, 1, 2, 3, 4, 5};
  std::array<int, kPoseDim> sign_{1, 1, 1, 1, 1, 1};
  std::array<double, kPoseDim> scale_{1.0, 1.0, 1.0, 1.0, 1.0, 1.0};
  std::array<double, kPoseDim> gain_{1.0, 1.0, 1.0, 1.0, 1.0, 1.0};
  Target target_{Target::kDelta};
  Frame frame_{Frame::kBase};
  int lag_{0};
  bool gripper_inverted_{false};
};

/// sha256 of the concatenated lowercase hex hashes, in order (`pool_sha256`; docs/reference.md, *Contracts*).
inline std::string pool_sha256(const std::vector<Contract>& pool) {
  std::string cat;
  cat.reserve(64 * pool.size());
  for (const auto& c : pool) cat += c.sha256();
  return sha256_hex(cat);
}

}  // namespace actionshift
