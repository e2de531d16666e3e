// `actionshift audit LOG` and `actionshift record` (issue 37, docs/audit.md).
#include "cmd_audit.hpp"

#include "cmd_selftest.hpp"

#include "actionshift/adapt/calibration.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/weight_file.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/selftest/audit.hpp"
#include "actionshift/selftest/audit_hdf5.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/task.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>

namespace actionshift::cli {

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

selftest::Conventions resolve_declared(const std::string& arg) {
  std::error_code ec;
  const bool is_file = arg.find('{') == std::string::npos && std::filesystem::is_regular_file(arg, ec);
  if (is_file || arg.find('{') != std::string::npos) {
    const std::string source = is_file ? arg : "--declared";
    const std::string text = is_file ? read_input_file(arg, "a declared convention", kMaxSmallFileBytes) : arg;
    return selftest::Conventions::from_json_value(parse_json_input(text, source), source);
  }
  selftest::Conventions c;
  c.contract = resolve_contract_arg(arg, "--declared");
  return c;
}

int audit(const AuditCliOptions& o) {
  if (!o.calibration.empty() && !o.task.empty()) throw InputError("command line", "--calibration", "give --calibration or --task, not both");
  selftest::ActionLog log = selftest::read_log(o.log);
  if (o.max_steps) {
    if (*o.max_steps < 1) throw InputError("command line", "--max-steps", "must be >= 1");
    log = log.head(static_cast<std::size_t>(*o.max_steps));
  }
  selftest::AuditOptions ao = o.audit;
  std::string declared_from = "default (identity)";
  if (!o.declared.empty()) {
    ao.declared = resolve_declared(o.declared);
    declared_from = "--declared";
  } else if (log.declared) {
    ao.declared = *log.declared;
    declared_from = log.declared_from;
  } else if (!log.declared_from.empty()) {  // the file names a convention the reader does not declare: why
    declared_from += "; " + log.declared_from;
  }
  if (!o.rotation.empty()) {
    auto r = selftest::parse_rotation_rep(o.rotation);
    if (!r) throw InputError("command line", "--rotation", "must be axis_angle, euler_xyz or euler_zyx (got " + quote_input(o.rotation) + ")");
    ao.declared.rotation = *r;
  }
  if (!o.gripper_range.empty()) {
    auto r = selftest::parse_gripper_range(o.gripper_range);
    if (!r) throw InputError("command line", "--gripper-range", "must be -1..1 or 0..1 (got " + quote_input(o.gripper_range) + ")");
    ao.declared.gripper_range = *r;
  }
  if (!o.action_kind.empty()) {
    auto r = selftest::parse_action_kind(o.action_kind);
    if (!r) throw InputError("command line", "--action-kind", "must be command, next_state or current_state (got " + quote_input(o.action_kind) + ")");
    ao.declared.action = *r;
  }
  std::string model_from = "fitted from the log";
  if (!o.calibration.empty()) {
    const auto cal = adapt::ResponseCalibration::load(o.calibration);
    ao.model = cal.model();
    model_from = o.calibration;
  } else if (!o.task.empty()) {
    const auto text = data::builtin_calibration_text(o.task, o.profile);
    if (!text)
      throw InputError("command line", "--task", "no built-in response calibration for task " + quote_input(o.task) + " on profile " +
                                                     quote_input(o.profile) + " (pass --calibration FILE)");
    ao.model = adapt::ResponseCalibration::from_json(std::string(*text), "built-in calibration " + o.profile + "/" + o.task).model();
    model_from = "built-in calibration " + o.profile + "/" + o.task;
  }
  if (const std::string err = selftest::validate(ao); !err.empty()) throw InputError("command line", "", err);
  const selftest::AuditResult r = selftest::audit(log, ao);
  if (o.json) {
    nlohmann::json j = selftest::to_json_value(r);
    j["declared_from"] = declared_from;
    j["model_from"] = model_from;
    j["layout"] = log.layout;
    j["confidence_floor"] = ao.confidence_floor;
    j["misspec_ratio"] = ao.misspec_ratio;
    j["gain_tolerance"] = ao.gain_tolerance;
    j["min_explained"] = ao.min_explained;
    j["outlier_z"] = ao.outlier_z;
    j["max_coupling"] = ao.max_coupling;
    j["min_margin"] = ao.min_margin;
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << selftest::to_text(r) << "Declared: " << declared_from << "; response model: " << model_from << "; layout: " << log.layout
              << "\n";
  }
  return r.exit_code();
}

int record(const RecordOptions& o) {
  if (o.out.empty()) throw InputError("command line", "--out", "required: the log file (.csv, .jsonl, .h5)");
  const bool h5 = ends_with(o.out, ".h5") || ends_with(o.out, ".hdf5");
  if (!h5 && !ends_with(o.out, ".csv") && !ends_with(o.out, ".jsonl"))
    throw InputError("command line", "--out", quote_input(o.out) + ": the name must end in .csv, .jsonl or .h5");
  if (o.layout != "maniskill" && o.layout != "robomimic") throw InputError("command line", "--layout", "must be maniskill or robomimic");
  require_replaceable_output(o.out);
  if (o.steps && *o.steps < 1) throw InputError("command line", "--steps", "must be >= 1");
  eval::JobSpec job;
  eval::EpisodeFnOptions eo;
  resolve_cli_job(o.job, job, eo);
  if (o.contract < 0 || o.contract >= job.split.contracts)
    throw InputError("command line", "--contract", std::to_string(o.contract) + " is outside the split's " + std::to_string(job.split.contracts) + " contracts");
  const sim::ObservationLayout& layout = sim::observation_layout(sim::parse_task(job.task));
  const int tcp = layout.at("tcp_pose").offset;
  const int qpos = layout.at("qpos").offset;

  selftest::ActionLog log;
  log.source = o.out;
  log.layout = h5 ? o.layout : (ends_with(o.out, ".csv") ? "csv" : "jsonl");
  eval::EpisodeHooks hooks;
  hooks.observer = [&](const eval::EpisodeStepView& v) {
    const Eigen::VectorXd& obs = v.result->obs;
    selftest::TcpPose p;
    p.position = Vec3(obs[tcp], obs[tcp + 1], obs[tcp + 2]);
    p.quaternion = Eigen::Vector4d(obs[tcp + 3], obs[tcp + 4], obs[tcp + 5], obs[tcp + 6]);
    p.fingers = Eigen::Vector2d(obs[qpos + 7], obs[qpos + 8]);
    auto& ep = log.episodes.back();
    ep.poses.push_back(p);
    if (v.raw) ep.actions.push_back(*v.raw);
  };
  const eval::EpisodeFn fn = eval::make_episode_fn(job, eo, std::move(hooks));
  int recorded = 0, successes = 0;
  for (std::int64_t i = 0; i < job.episodes; ++i) {
    const eval::EpisodeTask task = eval::episode_task(job, i);
    if (task.contract_index != o.contract) continue;
    log.episodes.emplace_back();
    const eval::EpisodeRecord rec = fn(task);
    ++recorded;
    successes += rec.success_once;
    if (o.steps && log.transitions() >= static_cast<std::size_t>(*o.steps)) break;
  }
  if (o.steps && log.transitions() > static_cast<std::size_t>(*o.steps)) log = log.head(static_cast<std::size_t>(*o.steps));
  if (log.transitions() == 0) throw InputError("command line", "--episodes", "no episode of contract " + std::to_string(o.contract) + " in this job");
  if (!h5) {
    if (ends_with(o.out, ".csv")) selftest::write_log_csv(log, o.out);
    else selftest::write_log_jsonl(log, o.out);
  } else if (o.layout == "maniskill") {
    selftest::write_log_maniskill(log, o.out, "pd_ee_delta_pose");
  } else {
    selftest::write_log_robomimic(log, o.out, "OSC_POSE");
  }
  const Contract truth = data::resolve_manifest(o.job.request.split).contracts().at(static_cast<std::size_t>(o.contract));
  if (!o.truth.empty()) {
    selftest::Conventions c;
    c.contract = truth;
    nlohmann::json j = c.to_json_value();
    j["recorded"] = {{"job_id", eval::job_id(job)}, {"split", job.split.name}, {"contract_index", o.contract}};
    write_file_atomic(o.truth, j.dump(2) + "\n");
  }
  nlohmann::json line{{"log", o.out},          {"job_id", eval::job_id(job)}, {"contract_index", o.contract},
                      {"episodes", recorded},  {"success_once", successes},   {"transitions", log.transitions()},
                      {"contract_sha256", truth.sha256()}};
  std::cout << line.dump() << "\n";
  return kOk;
}

}  // namespace

int run_audit(const AuditCliOptions& o) {
  try {
    return audit(o);
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

int run_record(const RecordOptions& o) {
  try {
    return record(o);
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

}  // namespace actionshift::cli
