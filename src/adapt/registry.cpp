#include "actionshift/adapt/registry.hpp"

#include "actionshift/adapt/grammar_belief.hpp"
#include "actionshift/adapt/identifier.hpp"
#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/plugin.hpp"
#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <set>
#include <string>

namespace actionshift::adapt {

const std::vector<std::string>& method_names() {
  static const std::vector<std::string> n{"oracle", "entropy_probes", "dualabi", "fixed_probes", "random_probes",
                                          "exact_belief", "grammar_belief", "osi", "probe_osi", "recurrent_osi",
                                          "no_adapt",       "delayed_oracle"};
  return n;
}

bool method_needs_pool(const std::string& m) {
  if (const auto plugin = find_method_plugin(m)) return plugin->rung == Rung::pool;
  return m != "oracle" && m != "delayed_oracle" && m != "no_adapt" && m != "grammar_belief" && !parse_identifier_kind(m);
}
bool method_needs_calibration(const std::string& m) {
  if (const auto plugin = find_method_plugin(m)) return plugin->rung == Rung::pool || plugin->rung == Rung::grammar;
  return method_needs_pool(m) || m == "grammar_belief";
}

namespace {

nlohmann::json defaults(const std::string& m) {
  if (const auto plugin = find_method_plugin(m)) return plugin->params;
  if (m == "oracle" || m == "no_adapt" || m == "exact_belief") return nlohmann::json::object();
  // a diagnostic: the oracle after 6 steps (the paper's probe budget) of the backbone's actions sent unchanged
  if (m == "delayed_oracle") return {{"delay", 6}, {"before", "no_adapt"}};
  if (m == "grammar_belief")  // the reference's operating points: 6 fixed pulses of 0.5; hold h2-r1 over 6 channels
    // the scale corrector's defaults are the reference's (§4.7: window 16, bounds 0.4..2.5, floor 0.05)
    return {{"probe", "none"},     {"budget", 6},        {"amplitude", 0.5},          {"hold_steps", 2},
            {"hold_rounds", 1},    {"hold_channels", 6}, {"after_probe", "belief"}, {"gripper_channel", false},
            {"scale_correction", false}, {"scale_window", 16}, {"scale_min", 0.4},  {"scale_max", 2.5},
            {"scale_floor", 0.05},  {"reanchor_period", 0}};
  // the learned identifiers: committed weights by name (configs/identifiers/<weights>.<method>.asid),
  // 8 steps of evidence before the first estimate; probe_osi sends the 6 fixed pulses of 0.5 first
  if (m == "osi" || m == "recurrent_osi") return {{"weights", "pick_cube"}, {"warmup", 8}};
  if (m == "probe_osi") return {{"weights", "pick_cube"}, {"warmup", 8}, {"budget", 6}, {"amplitude", 0.5}};
  nlohmann::json p = {{"budget", 6}, {"amplitude", 0.5}};
  // the paper's probe rule by default: an unscaled, lag-blind preview and the pure argmin (the
  // reference implementation's selection); the project's corrections are the named variant
  // `calibrated` (method_variants())
  if (m == "entropy_probes" || m == "dualabi") {
    p["calibrated_preview"] = false;
    p["lag_aware_preview"] = false;
    p["max_active"] = 32;
  }
  if (m == "entropy_probes") {
    p["entropy_tolerance"] = 0.0;
    p["motion_tiebreak"] = false;
  }
  if (m == "dualabi") {
    p["tau"] = 1.5;  // frozen by the pilot on seeds 20260723/24 (docs/results/dualabi_pilot.md); the reference also froze 1.5
    p["window"] = 8;
  }
  return p;
}

ProbeOptions probe_options(const nlohmann::json& p) {
  ProbeOptions o;
  o.budget = p.at("budget").get<int>();
  o.amplitude = p.at("amplitude").get<double>();
  if (p.contains("calibrated_preview")) o.calibrated_preview = p["calibrated_preview"].get<bool>();
  if (p.contains("lag_aware_preview")) o.lag_aware_preview = p["lag_aware_preview"].get<bool>();
  if (p.contains("max_active")) o.max_active = p["max_active"].get<int>();
  if (p.contains("entropy_tolerance")) o.entropy_tolerance = p["entropy_tolerance"].get<double>();
  if (p.contains("motion_tiebreak")) o.motion_tiebreak = p["motion_tiebreak"].get<bool>();
  return o;
}

}  // namespace

nlohmann::json resolve_method_params(const std::string& method, const nlohmann::json& params) {
  const auto& names = method_names();
  const auto plugin = find_method_plugin(method);
  if (!plugin && std::find(names.begin(), names.end(), method) == names.end()) {
    std::string known;
    for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
    for (const auto& n : method_plugin_names()) known += ", " + n;
    throw InputError("method", printable_input(method),
                     "unknown method (known: " + known + "; a method of your own must be registered first, docs/methods.md)");
  }
  if (!params.is_object()) throw InputError("method", method, "parameters must be a JSON object");
  nlohmann::json out = defaults(method);
  for (auto it = params.begin(); it != params.end(); ++it) {
    if (!out.contains(it.key())) {
      std::string known;
      for (auto k = out.begin(); k != out.end(); ++k) known += (known.empty() ? "" : ", ") + k.key();
      throw InputError("method " + method, printable_input(it.key()),
                       known.empty() ? "unknown parameter (this method takes none)" : "unknown parameter (known: " + known + ")");
    }
    const auto& d = out[it.key()];
    const auto& v = it.value();
    const bool ok = (d.is_string() && v.is_string()) || (d.is_boolean() && v.is_boolean()) || (d.is_number_integer() && v.is_number_integer()) ||
                    (d.is_number_float() && v.is_number());
    if (!ok) throw InputError("method " + method, it.key(), "wrong type (expected like " + d.dump() + ")");
    // every integer parameter is an int inside the adapters: a larger number would wrap around
    // (2**32 + 3 became 3) while the job recorded the number as given
    if (d.is_number_integer() &&
        (v.is_number_unsigned() ? v.get<std::uint64_t>() > static_cast<std::uint64_t>(std::numeric_limits<int>::max())
                                : (v.get<std::int64_t>() > std::numeric_limits<int>::max() ||
                                   v.get<std::int64_t>() < std::numeric_limits<int>::min())))
      throw InputError("method " + method, it.key(), "out of range (got " + v.dump() + ")");
    out[it.key()] = d.is_number_float() ? nlohmann::json(v.get<double>()) : v;
  }
  if (plugin) return out;  // a plug-in checks its own values (its factory may throw InputError)
  if (out.contains("budget") && (out["budget"].get<int>() < 0 || out["budget"].get<int>() > 1000))
    throw InputError("method " + method, "budget", "must be in [0, 1000]");
  if (out.contains("amplitude")) {
    const double a = out["amplitude"].get<double>();
    if (!(a > 0.0 && a <= 1.0)) throw InputError("method " + method, "amplitude", "must be in (0, 1]");
  }
  if (out.contains("max_active") && (out["max_active"].get<int>() < 1 || out["max_active"].get<int>() > 100000))
    throw InputError("method " + method, "max_active", "must be in [1, 100000]");
  if (out.contains("tau") && !(out["tau"].get<double>() >= 0.0 && std::isfinite(out["tau"].get<double>())))
    throw InputError("method " + method, "tau", "must be finite and nonnegative");
  if (out.contains("entropy_tolerance") && !(out["entropy_tolerance"].get<double>() >= 0.0))
    throw InputError("method " + method, "entropy_tolerance", "must be nonnegative");
  // DualABI's window holds one slot per step per pool member: bounded so a typo cannot allocate gigabytes
  if (out.contains("window") && (out["window"].get<int>() < 1 || out["window"].get<int>() > 1000))
    throw InputError("method " + method, "window", "must be in [1, 1000]");
  auto one_of = [&](const char* key, std::initializer_list<const char*> allowed) {
    if (!out.contains(key)) return;
    const auto v = out[key].get<std::string>();
    std::string list;
    for (const char* a : allowed) {
      if (v == a) return;
      list += (list.empty() ? "" : ", ") + std::string(a);
    }
    throw InputError("method " + method, key, "must be one of " + list + " (got " + quote_input(v) + ")");
  };
  one_of("probe", {"none", "fixed", "hold", "entropy"});
  one_of("after_probe", {"belief", "identity"});
  one_of("before", {"no_adapt", "hold"});
  auto int_in = [&](const char* key, int lo, int hi) {
    if (out.contains(key) && (out[key].get<int>() < lo || out[key].get<int>() > hi))
      throw InputError("method " + method, key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  };
  int_in("hold_steps", 2, 1000);
  int_in("hold_rounds", 1, 1000);
  int_in("hold_channels", 1, kPoseDim);
  int_in("scale_window", 1, 1000);
  int_in("reanchor_period", 0, 1000000);
  auto real_in = [&](const char* key, double lo, double hi, const char* what) {
    if (!out.contains(key)) return;
    const double v = out[key].get<double>();
    if (!std::isfinite(v) || v < lo || v > hi) throw InputError("method " + method, key, what);
  };
  real_in("scale_min", 1e-9, 1.0, "must be finite and in (0, 1]");
  real_in("scale_max", 1.0, 1e9, "must be finite and at least 1");
  real_in("scale_floor", 0.0, 1e9, "must be finite and nonnegative");
  int_in("warmup", 1, 1000);
  int_in("delay", 0, 1000000);
  if (out.contains("weights") && out["weights"].get<std::string>().empty())
    throw InputError("method " + method, "weights", "must name committed weights or a .asid file");
  return out;
}

std::unique_ptr<Adapter> make_adapter(const std::string& method, const nlohmann::json& given, const MethodInputs& in) {
  // resolved here as well (resolving resolved parameters changes nothing): a missing parameter takes
  // its default and a wrong one is a one-line InputError, never a JSON library exception
  const nlohmann::json p = resolve_method_params(method, given);
  if (const auto plugin = find_method_plugin(method)) {
    // exactly what the declared rung allows: never the truth; the pool only to the pool rung
    PluginInputs pi;
    pi.task = in.task;
    pi.rung = plugin->rung;
    pi.params = p;
    if (plugin->rung == Rung::pool) {
      if (!in.pool || in.pool->empty())
        throw InputError("method", method, "declares the pool rung and needs a pool (--pool on the command line, pool= in Python)");
      pi.pool = in.pool;
    }
    if (plugin->rung == Rung::pool || plugin->rung == Rung::grammar) {
      if (!in.model) throw InputError("method", method, "needs a response calibration");
      pi.model = in.model;
      pi.grammar = &grammar_grids();
    }
    auto adapter = plugin->factory(pi);
    if (!adapter) throw InputError("method", method, "its factory returned no adapter");
    return adapter;
  }
  if (method == "no_adapt") return std::make_unique<NoAdaptAdapter>();
  if (method == "grammar_belief") {  // grammar + calibration only: never given the truth or the pool
    if (!in.model) throw InputError("method", method, "needs a response calibration");
    GrammarOptions o;
    const auto probe = p.at("probe").get<std::string>();
    o.probe = probe == "fixed" ? GrammarProbe::kFixed : probe == "hold" ? GrammarProbe::kHold : GrammarProbe::kNone;
    o.budget = p.at("budget").get<int>();
    o.amplitude = p.at("amplitude").get<double>();
    o.hold = HoldSchedule(o.amplitude, p.at("hold_steps").get<int>(), p.at("hold_rounds").get<int>(), p.at("hold_channels").get<int>());
    o.belief_after_probe = p.at("after_probe").get<std::string>() == "belief";
    o.gripper_channel = p.at("gripper_channel").get<bool>();
    if (probe == "entropy") o.probe = GrammarProbe::kEntropy;
    if (p.at("scale_correction").get<bool>()) {
      ScaleCorrectorOptions sc;
      sc.window = p.at("scale_window").get<int>();
      sc.min_correction = p.at("scale_min").get<double>();
      sc.max_correction = p.at("scale_max").get<double>();
      sc.command_floor = p.at("scale_floor").get<double>();
      sc.fit = in.gain_fit;
      o.scale = sc;
    }
    o.reanchor_period = p.at("reanchor_period").get<int>();
    if (o.gripper_channel && !in.model->has_gripper())
      throw InputError("method grammar_belief", "gripper_channel",
                       "the task's calibration has no finger channel (run `actionshift calibrate --gripper-channel`)");
    return std::make_unique<GrammarBeliefAdapter>(*in.model, o);
  }
  if (const auto kind = parse_identifier_kind(method)) {  // the network only: never the truth, the pool or a calibration
    IdentifierOptions o;
    o.warmup = p.at("warmup").get<int>();
    if (*kind == IdentifierKind::kProbeOsi) {
      o.probe_budget = p.at("budget").get<int>();
      o.probe_amplitude = p.at("amplitude").get<double>();
      o.freeze = true;  // estimates once, from the window that holds the probes
    }
    return std::make_unique<IdentifierAdapter>(
        load_identifier_cached(identifier_weights_path(p.at("weights").get<std::string>(), *kind), *kind), o);
  }
  if (method == "oracle") {
    if (!in.truth) throw InputError("method", "oracle", "needs the true contract (given by the runner; truth= in Python)");
    return std::make_unique<OracleAdapter>(*in.truth);
  }
  if (method == "delayed_oracle") {
    if (!in.truth) throw InputError("method", method, "needs the true contract (given by the runner; truth= in Python)");
    return std::make_unique<DelayedOracleAdapter>(
        *in.truth, p.at("delay").get<int>(),
        p.at("before").get<std::string>() == "hold" ? DelayedOracleAdapter::Before::kHold : DelayedOracleAdapter::Before::kNoAdapt);
  }
  if (!in.pool || in.pool->empty()) throw InputError("method", method, "needs a pool of candidate contracts (--pool on the command line, pool= in Python)");
  if (!in.model) throw InputError("method", method, "needs a response calibration");
  if (method == "exact_belief") return std::make_unique<ExactBeliefAdapter>(*in.pool, *in.model);
  if (method == "fixed_probes") return std::make_unique<ProbingAdapter>(*in.pool, *in.model, ProbeStrategy::kFixed, probe_options(p));
  if (method == "random_probes") return std::make_unique<ProbingAdapter>(*in.pool, *in.model, ProbeStrategy::kRandom, probe_options(p));
  if (method == "entropy_probes")
    return std::make_unique<ProbingAdapter>(*in.pool, *in.model, ProbeStrategy::kEntropy, probe_options(p));
  if (method == "dualabi")
    return std::make_unique<DualAbiAdapter>(*in.pool, *in.model, p.at("tau").get<double>(), probe_options(p),
                                            p.at("window").get<int>());
  throw InputError("method", method, "unknown method");
}

}  // namespace actionshift::adapt

namespace actionshift::adapt {

const std::vector<MethodVariant>& method_variants() {
  static const std::vector<MethodVariant> v{
      {"entropy_probes", "calibrated",
       {{"calibrated_preview", true}, {"lag_aware_preview", true}, {"entropy_tolerance", 0.001}, {"motion_tiebreak", true}},
       "previews each hypothesis as the calibrated response alpha*prediction through its own lag FIFO (the paper's "
       "rule compares unscaled, lag-blind predictions with a scaled observation), and among probes within 0.001 nats "
       "of the best sends the one that moves the arm least"},
      {"dualabi", "calibrated",
       {{"calibrated_preview", true}, {"lag_aware_preview", true}},
       "previews each hypothesis as the calibrated response alpha*prediction through its own lag FIFO (the paper's "
       "rule compares unscaled, lag-blind predictions with a scaled observation)"},
  };
  return v;
}

namespace {

const MethodVariant* find_variant(const std::string& method, std::string_view name) {
  for (const auto& v : method_variants())
    if (v.method == method && v.name == name) return &v;
  return nullptr;
}

std::string trim(std::string_view s) {
  std::size_t a = 0, b = s.size();
  while (a < b && (s[a] == ' ' || s[a] == '\t')) ++a;
  while (b > a && (s[b - 1] == ' ' || s[b - 1] == '\t')) --b;
  return std::string(s.substr(a, b - a));
}

// a label value: true/false, an integer, a decimal, a JSON string, or bare text
nlohmann::json label_value(const std::string& text, const std::string& where) {
  if (text.empty()) throw InputError("method", where, "missing value after '='");
  if (text == "true") return true;
  if (text == "false") return false;
  if (text.front() == '"') {
    try {
      const auto j = nlohmann::json::parse(text);
      if (j.is_string()) return j;
    } catch (const nlohmann::json::exception&) {
    }
    throw InputError("method", where, "malformed quoted value " + quote_input(text));
  }
  const bool numeric = text.find_first_not_of("0123456789+-.eE") == std::string::npos &&
                       text.find_first_of("0123456789") != std::string::npos;
  if (numeric) {
    try {
      const auto j = nlohmann::json::parse(text);
      if (j.is_number()) return j;
    } catch (const nlohmann::json::exception&) {
    }
    throw InputError("method", where, "malformed number " + quote_input(text));
  }
  return text;
}

std::string label_text(const nlohmann::json& v) {
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_float()) return python_float_repr(v.get<double>());
  if (v.is_number()) return v.dump();
  if (v.is_string()) {
    const auto s = v.get<std::string>();
    const bool bare = !s.empty() && s != "true" && s != "false" && s.find_first_of(",{}=\" ") == std::string::npos &&
                      s.find_first_not_of("0123456789+-.eE") != std::string::npos;
    return bare ? s : v.dump();
  }
  return v.dump();
}

// equal as parameter values: numbers by value (0 and 0.0 alike), everything else exactly
bool same_value(const nlohmann::json& a, const nlohmann::json& b) {
  if (a.is_number() && b.is_number()) return a.get<double>() == b.get<double>();
  return a == b;
}

}  // namespace

MethodLabel parse_method_label(std::string_view label) {
  MethodLabel out;
  const std::size_t open = label.find('{');
  if (open == std::string_view::npos) {
    if (label.find('}') != std::string_view::npos) throw InputError("method", printable_input(label), "'}' without '{'");
    out.name = std::string(label);
    return out;
  }
  if (label.back() != '}') throw InputError("method", printable_input(label), "a label's parameters end with '}'");
  out.name = std::string(label.substr(0, open));
  if (out.name.empty()) throw InputError("method", printable_input(label), "no method name before '{'");
  const std::string_view body = label.substr(open + 1, label.size() - open - 2);
  // split at commas outside quotes
  std::vector<std::string> items;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < body.size(); ++i) {
    const char c = body[i];
    if (c == '"' && (i == 0 || body[i - 1] != '\\')) quoted = !quoted;
    if (c == ',' && !quoted) {
      items.push_back(trim(cur));
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (quoted) throw InputError("method", printable_input(label), "unterminated quoted value");
  items.push_back(trim(cur));
  if (items.size() == 1 && items[0].empty()) return out;  // name{}: the defaults
  std::set<std::string> explicit_keys;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const std::string& item = items[i];
    if (item.empty()) throw InputError("method", printable_input(label), "empty item between commas");
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || (item.front() == '"')) {
      const MethodVariant* v = find_variant(out.name, item);
      if (!v) {
        std::string known;
        for (const auto& mv : method_variants())
          if (mv.method == out.name) known += (known.empty() ? "" : ", ") + mv.name;
        throw InputError("method " + out.name, printable_input(item),
                         known.empty() ? "unknown variant (this method has no named variants; give key=value)"
                                       : "unknown variant (known: " + known + ")");
      }
      if (i != 0) throw InputError("method " + out.name, item, "a named variant comes first in the label");
      for (auto it = v->params.begin(); it != v->params.end(); ++it) out.params[it.key()] = it.value();
      continue;
    }
    const std::string key = trim(item.substr(0, eq));
    if (key.empty()) throw InputError("method " + out.name, printable_input(item), "missing parameter name before '='");
    const nlohmann::json value = label_value(trim(item.substr(eq + 1)), key);
    // a key the variant set may be overridden; a key given twice may not
    if (!explicit_keys.insert(key).second) throw InputError("method " + out.name, key, "given twice in the label");
    out.params[key] = value;
  }
  return out;
}

nlohmann::json merge_method_params(const MethodLabel& label, const nlohmann::json& explicit_params) {
  if (!explicit_params.is_object()) throw InputError("method " + label.name, "params", "not a JSON object");
  nlohmann::json out = label.params;
  for (auto it = explicit_params.begin(); it != explicit_params.end(); ++it) {
    if (out.contains(it.key()) && !same_value(out[it.key()], it.value()))
      throw InputError("method " + label.name, it.key(),
                       "set to " + label_text(out[it.key()]) + " by the label and to " + label_text(it.value()) + " by params");
    out[it.key()] = it.value();
  }
  return out;
}

std::string method_variant_label(const std::string& method, const nlohmann::json& p) {
  const nlohmann::json d = defaults(method);
  // the variant whose every parameter matches and that sets the most
  const MethodVariant* best = nullptr;
  for (const auto& v : method_variants()) {
    if (v.method != method) continue;
    bool all = true;
    for (auto it = v.params.begin(); it != v.params.end() && all; ++it) all = p.contains(it.key()) && same_value(p[it.key()], it.value());
    if (all && (!best || v.params.size() > best->params.size())) best = &v;
  }
  std::vector<std::string> items;
  if (best) items.push_back(best->name);
  for (auto it = p.begin(); it != p.end(); ++it) {  // nlohmann objects iterate in sorted key order
    const nlohmann::json* base = nullptr;
    if (best && best->params.contains(it.key())) base = &best->params[it.key()];
    else if (d.contains(it.key())) base = &d[it.key()];
    if (base && same_value(*base, it.value())) continue;
    items.push_back(it.key() + "=" + label_text(it.value()));
  }
  if (items.empty()) return method;
  std::string out = method + "{";
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? "," : "") + items[i];
  return out + "}";
}

}  // namespace actionshift::adapt
