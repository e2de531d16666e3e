#include "actionshift/adapt/calibration.hpp"
#include "actionshift/core/input_file.hpp"

#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/vocabulary.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace actionshift::adapt {

namespace {
constexpr const char* kSchema = "actionshift-calibration/2";
constexpr const char* kSchemaV1 = "actionshift-calibration/1";
}

LinearFit fit_linear_response(const std::vector<Pose6>& x, const std::vector<Pose6>& y) {
  if (x.empty() || x.size() != y.size())
    throw std::invalid_argument("fit_linear_response: need the same non-zero number of commands and responses");
  LinearFit f;
  const double n = static_cast<double>(x.size());
  for (int c = 0; c < kPoseDim; ++c) {
    const auto k = static_cast<std::size_t>(c);
    double sxy = 0, sxx = 0, sy = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      sxy += x[i][c] * y[i][c];
      sxx += x[i][c] * x[i][c];
      sy += y[i][c];
    }
    const double a = sxx > 0 ? sxy / sxx : 0.0;
    const double ybar = sy / n;
    double srr = 0, sr = 0, stt = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double r = y[i][c] - a * x[i][c];
      srr += r * r;
      sr += r;
      stt += (y[i][c] - ybar) * (y[i][c] - ybar);
    }
    const double var = srr / n - (sr / n) * (sr / n);  // population variance of the residual
    f.alpha[k] = a;
    f.sigma[k] = std::max(std::sqrt(std::max(var, 0.0)), 1e-4);
    f.fit_r2[k] = stt > 0 ? 1.0 - srr / stt : 0.0;
  }
  return f;
}

GripperFit fit_gripper_response(const std::vector<double>& x, const std::vector<double>& y, int start) {
  if (x.empty() || x.size() != y.size())
    throw std::invalid_argument("fit_gripper_response: need the same non-zero number of commands and responses");
  std::vector<Pose6> px(x.size(), Pose6::Zero()), py(y.size(), Pose6::Zero());
  for (std::size_t i = 0; i < x.size(); ++i) {
    px[i][0] = x[i];
    py[i][0] = y[i];
  }
  const LinearFit f = fit_linear_response(px, py);
  return {start, f.alpha[0], f.sigma[0], f.fit_r2[0]};
}

std::string ResponseCalibration::to_json() const {
  nlohmann::json j;
  j["schema_version"] = kSchema;
  j["task"] = task;
  j["position_start"] = slice.position_start;
  j["quaternion_start"] = slice.quaternion_start;
  j["alpha"] = fit.alpha;
  j["sigma"] = fit.sigma;
  j["fit_r2"] = fit.fit_r2;
  j["episodes"] = episodes;
  j["steps"] = steps;
  j["seed"] = seed;
  j["rotation_mode"] = rotation_mode;
  j["profile"] = profile;
  j["protocol"] = protocol;
  if (gripper)
    j["gripper"] = {{"start", gripper->start}, {"alpha", gripper->alpha}, {"sigma", gripper->sigma}, {"fit_r2", gripper->fit_r2}};
  return canonical_dump(j);
}

std::string ResponseCalibration::sha256() const { return sha256_hex(to_json()); }

ResponseCalibration ResponseCalibration::from_json(const std::string& text, const std::string& source) {
  const nlohmann::json j = parse_json_input(text, source);
  if (!j.is_object()) throw InputError(source, "", "calibration must be a JSON object");
  if (!j.contains("schema_version")) throw InputError(source, "schema_version", "missing field");
  const bool v1 = j["schema_version"] == kSchemaV1;
  if (!v1 && j["schema_version"] != kSchema)
    throw InputError(source, "schema_version", std::string("expected '") + kSchema + "' (or '" + kSchemaV1 + "')");
  static const char* kKeys[] = {"schema_version", "task", "position_start", "quaternion_start", "alpha", "sigma",
                                "fit_r2", "episodes", "steps", "seed", "rotation_mode", "profile", "protocol"};
  const std::size_t nkeys = v1 ? 11 : 13;
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool known = false;
    for (std::size_t k = 0; k < nkeys; ++k) known = known || it.key() == kKeys[k];
    known = known || (!v1 && it.key() == "gripper");
    if (!known) throw InputError(source, it.key(), "unknown field");
  }
  for (std::size_t k = 0; k < nkeys; ++k)
    if (!j.contains(kKeys[k])) throw InputError(source, kKeys[k], "missing field");
  ResponseCalibration c;
  auto str = [&](const char* k) {
    if (!j[k].is_string()) throw InputError(source, k, "must be a string");
    return j[k].get<std::string>();
  };
  auto integer = [&](const char* k, long long lo) {
    if (!j[k].is_number_integer() || j[k].get<long long>() < lo)
    {
      std::string msg = "must be an integer >= ";
      msg += std::to_string(lo);
      throw InputError(source, k, msg);
    }
    return j[k].get<long long>();
  };
  auto six = [&](const char* k, std::array<double, kPoseDim>& out) {
    if (!j[k].is_array() || j[k].size() != 6) throw InputError(source, k, "must be a list of 6 numbers");
    for (std::size_t i = 0; i < 6; ++i) {
      if (!j[k][i].is_number()) throw InputError(source, k, "must be a list of 6 numbers");
      out[i] = j[k][i].get<double>();
      if (!std::isfinite(out[i])) throw InputError(source, k, "must be finite");
    }
  };
  c.task = str("task");
  c.rotation_mode = str("rotation_mode");
  c.profile = v1 ? "ideal" : str("profile");
  c.protocol = v1 ? "episodes" : str("protocol");
  if (c.protocol != "maniskill_walk" && c.protocol != "reference_walk" && c.protocol != "episodes")
    throw InputError(source, "protocol", "must be 'maniskill_walk', 'reference_walk' or 'episodes'");
  c.slice.position_start = static_cast<int>(integer("position_start", 0));
  c.slice.quaternion_start = static_cast<int>(integer("quaternion_start", 0));
  c.episodes = static_cast<int>(integer("episodes", 1));
  c.steps = static_cast<int>(integer("steps", 2));
  if (!j["seed"].is_number_unsigned()) throw InputError(source, "seed", "must be a nonnegative integer");
  c.seed = j["seed"].get<std::uint64_t>();
  six("alpha", c.fit.alpha);
  six("sigma", c.fit.sigma);
  six("fit_r2", c.fit.fit_r2);
  if (j.contains("gripper")) {
    const auto& g = j["gripper"];
    if (!g.is_object()) throw InputError(source, "gripper", "must be an object {alpha, fit_r2, sigma, start}");
    for (auto it = g.begin(); it != g.end(); ++it)
      if (it.key() != "alpha" && it.key() != "fit_r2" && it.key() != "sigma" && it.key() != "start")
        throw InputError(source, "gripper." + it.key(), "unknown field");
    GripperFit gf;
    for (const char* k : {"alpha", "fit_r2", "sigma"}) {
      if (!g.contains(k) || !g[k].is_number() || !std::isfinite(g[k].get<double>()))
        throw InputError(source, std::string("gripper.") + k, "must be a finite number");
    }
    if (!g.contains("start") || !g["start"].is_number_integer() || g["start"].get<long long>() < 0)
      throw InputError(source, "gripper.start", "must be an integer >= 0");
    gf.start = static_cast<int>(g["start"].get<long long>());
    gf.alpha = g["alpha"].get<double>();
    gf.sigma = g["sigma"].get<double>();
    gf.fit_r2 = g["fit_r2"].get<double>();
    if (!(gf.sigma > 0.0)) throw InputError(source, "gripper.sigma", "must be positive");
    if (gf.alpha == 0.0) throw InputError(source, "gripper.alpha", "must be non-zero");
    c.gripper = gf;
  }
  try {
    c.model().validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(source, "alpha/sigma", e.what());
  }
  // what a fit can produce: sigma is floored at 1e-4 when fitted (a smaller one would make the belief
  // certain after one step), R^2 is at most 1, and a gain is a response per unit command (|alpha| <= 1e3)
  for (std::size_t i = 0; i < 6; ++i) {
    if (c.fit.sigma[i] < 1e-4) throw InputError(source, "sigma", "must be at least 1e-4 (the fit's floor)");
    if (c.fit.fit_r2[i] > 1.0) throw InputError(source, "fit_r2", "must be at most 1");
    if (std::abs(c.fit.alpha[i]) > 1e3) throw InputError(source, "alpha", "must be at most 1e3 in magnitude");
  }
  if (parse_rotation_mode(c.rotation_mode, source, "rotation_mode") != RotationMode::kLive)
    throw InputError(source, "rotation_mode", "must be 'live' (got '" + c.rotation_mode + "')");
  return c;
}

ResponseCalibration ResponseCalibration::load(const std::string& path) {
  return from_json(read_input_file(path, "a calibration file", kMaxSmallFileBytes), path);
}

ResponseCalibration ResponseCalibration::load_for(const std::string& path, const std::string& task, const std::string& task_name,
                                              const std::string& profile, const std::string& profile_name) {
  ResponseCalibration cal = load(path);
  if (cal.task != task) throw InputError(path, "task", "is " + cal.task + ", not " + task_name);
  const std::string base = cal.profile.substr(0, cal.profile.find('['));
  if (base != profile) throw InputError(path, "profile", "was measured on " + cal.profile + ", not on " + profile_name);
  return cal;
}

}  // namespace actionshift::adapt
