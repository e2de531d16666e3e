// `actionshift selftest`: resolves the arguments, builds a SelfTest, drives it against the synthetic
// stand-in or the Bullet environment (the library itself never links the simulator), prints the report.
#include "cmd_selftest.hpp"

#include "actionshift/adapt/calibration.hpp"
#include "actionshift/core/atomic_file.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/sim/task.hpp"
#include "actionshift/selftest/library.hpp"
#include "actionshift/selftest/selftest.hpp"
#include "actionshift/selftest/synthetic_robot.hpp"
#include "actionshift/sim/controller.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"
#include "actionshift/sim/robot_source.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

namespace actionshift::cli {

namespace {

std::string read_text(const std::string& path, const std::string& what) { return read_input_file(path, what, kMaxSmallFileBytes); }

std::vector<Contract> resolve_pool(const std::vector<std::string>& names) {
  std::vector<Contract> pool;
  for (const auto& n : names) {
    if (n == "library") {
      for (const auto& c : selftest::library()) pool.push_back(c.contract);
    } else {
      for (const auto& c : data::resolve_manifest(n).contracts()) pool.push_back(c);
    }
  }
  std::vector<Contract> unique;  // keep the first occurrence (MAP ties go to the lowest index)
  for (auto& c : pool)
    if (std::find(unique.begin(), unique.end(), c) == unique.end()) unique.push_back(std::move(c));
  return unique;
}

adapt::ResponseCalibration load_calibration(const SelftestOptions& o) {
  if (!o.calibration.empty()) {
    auto cal = adapt::ResponseCalibration::load_for(o.calibration, o.task, "--task " + o.task, o.profile, "--profile " + o.profile);
    // the same checks as `run --calibration`: a layout `run` refuses is refused here too
    eval::check_calibration_layout(cal, sim::observation_layout(sim::parse_task(o.task)), o.task, o.calibration);
    return cal;
  }
  if (auto text = data::builtin_selftest_calibration_text(o.task, o.profile))
    return adapt::ResponseCalibration::from_json(std::string(*text), "built-in calibration " + o.profile + "/selftest/" + o.task);
  throw InputError("", "--calibration",
                   "no built-in response calibration for task " + quote_input(o.task) + " in this build: pass --calibration FILE");
}

selftest::TcpPose pose_from_obs(const Eigen::VectorXd& obs, const sim::ObservationLayout& layout) {
  const sim::ObsField& tcp = layout.at("tcp_pose");
  selftest::TcpPose p;
  p.position = obs.segment<3>(tcp.offset);
  p.quaternion = obs.segment<4>(tcp.offset + 3);
  if (const sim::ObsField* q = layout.find("qpos"); q && q->width == 9) p.fingers = obs.segment<2>(q->offset + 7);
  return p;
}

// drives the self-test against the Bullet environment under the hidden contract; returns a note if
// the episode ended early
std::string run_sim(selftest::SelfTest& st, const Contract& hidden, const SelftestOptions& o,
                    const std::shared_ptr<const sim::EnvModel>& model, std::uint64_t seed) {
  sim::HiddenContractEnv env(model, hidden,
                             parse_rotation_mode(o.frame_rotation, "", "--frame-rotation"));
  st.begin(pose_from_obs(env.reset(seed), env.layout()));
  while (auto raw = st.next_probe()) {
    const sim::StepResult& r = env.step(*raw);
    if (r.safety != sim::SafetyFlag::kNone)
      return "the environment ended the episode with safety flag " + std::string(sim::safety_flag_name(r.safety)) +
             " after " + std::to_string(st.probes_observed()) + " probes";
    st.observe(pose_from_obs(r.obs, env.layout()));
    if (r.episode_over() && !st.done())
      return "the episode reached the task horizon after " + std::to_string(st.probes_observed()) + " probes";
  }
  return {};
}

// `--sim --calibrate-misspec FILE`: the misspecification thresholds from the simulator's own
// residuals. Every member of the declared pool is the hidden wiring in turn (so the true wiring is
// in the pool), over kMisspecCalibrationSeeds initial states; the fit ratios of the runs that
// identified the true wiring are the residuals of a correct hypothesis on this simulator. They are
// split by the target type of the wiring (the calibrated gain describes delta commands, so absolute
// wirings fit on another scale), and each threshold is that class's largest fit ratio times
// kMisspecCalibrationMargin. The task's entry of FILE is (re)written.
// the --sim environment: the task on the chosen fidelity profile and robot description
std::shared_ptr<const sim::EnvModel> sim_model(const SelftestOptions& o) {
  std::shared_ptr<const sim::RobotDescription> robot;
  if (!o.robot.urdf.empty()) robot = sim::load_robot_source(o.robot.urdf, sim::parse_package_args(o.robot.packages)).description;
  return sim::EnvModel::make(sim::parse_task(o.task), sim::profile_config(o.profile), robot);
}

int calibrate_misspec(const SelftestOptions& o, const selftest::Options& base, const adapt::ResponseCalibration& cal) {
  const auto model = sim_model(o);
  std::map<std::string, std::vector<double>> fits;  // by target type of the true wiring
  int misidentified = 0, cut_short = 0;
  for (const Contract& hidden : base.pool) {
    for (int k = 0; k < kMisspecCalibrationSeeds; ++k) {
      selftest::SelfTest st(base);
      if (!run_sim(st, hidden, o, model, o.seed + static_cast<std::uint64_t>(k)).empty()) {
        ++cut_short;
        continue;
      }
      const selftest::Evidence e = st.evidence();
      if (e.identified == hidden) fits[hidden.target() == Target::kAbsolute ? "absolute" : "delta"].push_back(e.fit_ratio);
      else ++misidentified;
    }
  }
  if (fits["delta"].empty())
    throw InputError(o.task, "--calibrate-misspec", "no delta wiring of the pool was identified: nothing to calibrate on");
  nlohmann::json entry = {{"margin", kMisspecCalibrationMargin},
                          {"runs_misidentified", misidentified},
                          {"runs_cut_short", cut_short},
                          {"pool_size", base.pool.size()},
                          {"seeds", {{"first", o.seed}, {"count", kMisspecCalibrationSeeds}}},
                          {"budget", base.budget},
                          {"amplitude", base.amplitude},
                          {"strategy", o.strategy},
                          {"frame_rotation", o.frame_rotation},
                          {"calibration_sha256", cal.sha256()}};
  std::string summary;
  for (auto& [cls, v] : fits) {
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    const double threshold = v.back() * kMisspecCalibrationMargin;
    entry[cls] = {{"misspec_ratio", threshold},
                  {"max_fit_ratio", v.back()},
                  {"median_fit_ratio", v[v.size() / 2]},
                  {"runs_identified", v.size()}};
    char line[160];
    std::snprintf(line, sizeof line, "%s%s %.4g (max fit %.4g x %.2g over %zu runs)", summary.empty() ? "" : ", ", cls.c_str(),
                  threshold, v.back(), kMisspecCalibrationMargin, v.size());
    summary += line;
  }
  nlohmann::json all = nlohmann::json::object();
  std::error_code ec;
  if (std::filesystem::is_regular_file(o.calibrate_misspec, ec)) all = parse_json_input(read_text(o.calibrate_misspec, "a misspecification file"), o.calibrate_misspec);
  if (!all.is_object()) throw InputError(o.calibrate_misspec, "", "expected a JSON object of tasks");
  all[o.task] = entry;
  write_file_atomic(o.calibrate_misspec, all.dump(2) + "\n");
  std::cout << "misspecification thresholds for " << o.task << ": " << summary << "; " << misidentified
            << " runs misidentified, " << cut_short << " cut short; written to " << o.calibrate_misspec << "\n";
  return 0;
}

int run(const SelftestOptions& o) {
  if (!o.demo.empty() && !o.hidden_contract.empty())
    throw InputError("", "--demo", "--demo and --hidden-contract are mutually exclusive");
  if (o.sim && !o.demo.empty()) throw InputError("", "--demo", "--demo is synthetic; use --hidden-contract with --sim");
  if (o.strategy != "fixed" && o.strategy != "entropy")
    throw InputError("", "--strategy", "must be fixed or entropy (got " + quote_input(o.strategy) + ")");
  const RotationMode rotation = parse_rotation_mode(o.frame_rotation, "", "--frame-rotation");
  if (!o.sim && rotation != RotationMode::kLive) throw InputError("", "--frame-rotation", "only applies with --sim");
  if (!o.sim && !o.calibration.empty()) throw InputError("", "--calibration", "only applies with --sim");
  if (!o.sim && (!o.robot.urdf.empty() || !o.robot.packages.empty()))
    throw InputError("", "--robot", "only applies with --sim");
  if (o.robot.urdf.empty() && !o.robot.packages.empty()) throw InputError("", "--package", "needs --robot URDF");

  selftest::Options so;
  so.expected = resolve_contract_arg(o.expected, "--expected");
  Contract hidden = so.expected;
  if (!o.demo.empty()) {
    bool found = false;
    for (const auto& d : selftest::demos())
      if (d.name == o.demo) {
        hidden = d.contract;
        found = true;
      }
    if (!found)
      throw InputError("", "--demo",
                       "unknown demo " + quote_input(o.demo) + " (identity, swapped-axes, sign-flip, miswired, scaled, reversed, lagged, unmodeled)");
  } else if (!o.hidden_contract.empty()) {
    hidden = resolve_contract_arg(o.hidden_contract, "--hidden-contract");
  }
  std::vector<std::string> pool_names = o.pools;
  if (pool_names.empty()) pool_names = o.sim ? std::vector<std::string>{"library", "reference9"} : std::vector<std::string>{"library"};
  so.pool = selftest::with_expected(resolve_pool(pool_names), so.expected);
  so.strategy = o.strategy == "fixed" ? selftest::Strategy::kFixed : selftest::Strategy::kEntropy;
  so.budget = o.budget.value_or(o.sim ? kSimDefaultBudget : 6);
  so.amplitude = o.amplitude.value_or(o.sim ? kSimDefaultAmplitude : 0.5);
  so.confidence_floor = o.confidence_floor;
  if (!o.sim && !o.calibrate_misspec.empty()) throw InputError("", "--calibrate-misspec", "only applies with --sim");
  std::string misspec_source = o.misspec_ratio ? "--misspec-ratio" : "default";
  if (o.misspec_ratio) {
    so.misspec_ratio = *o.misspec_ratio;
  } else if (!o.sim) {
    so.misspec_ratio = kSyntheticMisspecRatio;
  } else if (const auto calibrated = data::builtin_selftest_misspec_ratio(o.task, "delta")) {
    so.misspec_ratio = *calibrated;
    so.misspec_ratio_absolute = data::builtin_selftest_misspec_ratio(o.task, "absolute");
    misspec_source = "calibrated on the simulator's residuals";
  } else {
    so.misspec_ratio = kUncalibratedSimMisspecRatio;
    misspec_source = "uncalibrated default";
  }

  // the report names the task, so it is one of the five with or without --sim
  const sim::TaskId task_id = [&] {
    try {
      return sim::parse_task(o.task);
    } catch (const InputError& e) {
      throw InputError("", "--task", e.reason());  // the reason names the valid tasks
    }
  }();
  selftest::ReportHeader h;
  h.task = o.task;
  h.strategy = o.strategy;
  std::string note;
  std::optional<selftest::SelfTest> st;
  std::string err;
  if (o.sim) {
    const sim::TaskId task = task_id;
    if (so.budget > sim::task_horizon(task))
      throw InputError("", "--budget", "must be at most the task horizon " + std::to_string(sim::task_horizon(task)) +
                                           " with --sim (got " + std::to_string(so.budget) + ")");
    const auto cal = load_calibration(o);
    so.model = cal.model();
    so.frame_rotation = parse_rotation_mode(o.frame_rotation, "", "--frame-rotation");
    so.gripper = selftest::GripperMap{sim::kFingerTargetOffset, sim::kFingerTargetGain};  // probes hold the fingers
    char ratio[96];
    if (so.misspec_ratio_absolute)
      std::snprintf(ratio, sizeof ratio, "%.3g (delta wirings), %.3g (absolute)", so.misspec_ratio, *so.misspec_ratio_absolute);
    else
      std::snprintf(ratio, sizeof ratio, "%.3g", so.misspec_ratio);
    h.backend = "Bullet simulator, calibration " + cal.sha256().substr(0, 12) + ", frame rotation " + o.frame_rotation +
                ", misspecification threshold " + ratio + " x noise (" + misspec_source + ")";
    h.unit = "m";
    st = selftest::SelfTest::create(so, &err);
    if (!st) throw InputError("", "selftest", err);
    if (!o.calibrate_misspec.empty()) return calibrate_misspec(o, st->options(), cal);
    note = run_sim(*st, hidden, o, sim_model(o), o.seed);
  } else {
    so.frame_rotation = selftest::FrameRotation::kIdentity;  // the stand-in decodes with R = I (docs/reference.md, *Self-test*)
    h.backend = "synthetic stand-in: alpha 1, sigma 0.05, R = I";
    h.unit = "synthetic units";
    st = selftest::SelfTest::create(so, &err);
    if (!st) throw InputError("", "selftest", err);
    selftest::SyntheticRobot robot(hidden, so.model, o.seed);
    selftest::run(*st, robot);
  }
  h.budget = so.budget;
  h.pool_size = static_cast<int>(st->pool().size());

  selftest::Verdict v = st->verdict();
  if (!note.empty() && v.status == selftest::Status::kPass) {  // never pass on a cut-short probe
    v.status = selftest::Status::kInconclusive;
    v.reason = note + ". Abstaining.";
  } else if (!note.empty()) {
    v.reason += " (note: " + note + ")";
  }
  std::cout << (o.json ? selftest::to_json(v, h) + "\n" : selftest::to_text(v, h));
  return v.exit_code();
}

}  // namespace

// a contract argument: library name, MANIFEST:INDEX, file with contract JSON, or inline JSON
Contract resolve_contract_arg(const std::string& arg, const std::string& option) {
  if (auto c = selftest::named_contract(arg)) return *c;
  if (const auto colon = arg.rfind(':'); colon != std::string::npos && colon + 1 < arg.size() &&
                                         arg.find_first_not_of("0123456789", colon + 1) == std::string::npos &&
                                         arg.find('{') == std::string::npos) {
    const Manifest m = data::resolve_manifest(arg.substr(0, colon));
    const auto cs = m.contracts();
    std::size_t i = 0;
    const std::string digits = arg.substr(colon + 1);
    const auto parsed = std::from_chars(digits.data(), digits.data() + digits.size(), i);
    if (parsed.ec != std::errc() || i >= cs.size())
      throw InputError("", option, quote_input(arg) + ": index out of range (the manifest has " + std::to_string(cs.size()) +
                                       " contracts)");
    return cs[i];
  }
  std::error_code ec;
  const bool is_file = arg.find('{') == std::string::npos && std::filesystem::is_regular_file(arg, ec);
  const std::string text = is_file ? read_text(arg, "a contract file") : arg;
  if (!is_file && arg.find('{') == std::string::npos)
    throw InputError("", option,
                     quote_input(arg) + " is not a library name (" + selftest::named_contract_list() +
                         "), MANIFEST:INDEX, a contract file or contract JSON");
  try {
    return Contract::from_json(text);
  } catch (const std::invalid_argument& e) {
    throw InputError(is_file ? arg : "", option, e.what());
  }
}


int run_selftest(const SelftestOptions& o) {
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kSelftestBadInput;
  }
}

}  // namespace actionshift::cli
