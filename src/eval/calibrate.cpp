#include "actionshift/eval/calibrate.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/rng.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace actionshift::eval {

adapt::TcpSlice tcp_slice(const sim::ObservationLayout& layout) {
  const sim::ObsField* f = layout.find("tcp_pose");
  if (!f || f->width != 7) throw std::invalid_argument("observation layout has no 7-wide tcp_pose field");
  return {f->offset, f->offset + 3};
}

int finger_start(const sim::ObservationLayout& layout) {
  const sim::ObsField* f = layout.find("qpos");
  if (!f || f->width != 9) throw std::invalid_argument("observation layout has no 9-wide qpos field");
  return f->offset + 7;
}

void check_calibration_layout(const adapt::ResponseCalibration& cal, const sim::ObservationLayout& layout,
                              const std::string& task, const std::string& source) {
  const adapt::TcpSlice slice = tcp_slice(layout);
  const auto check = [&](const char* field, int is, int want) {
    if (is != want)
      throw InputError(source, field, "is " + std::to_string(is) + ", but " + task + "'s observation has it at " + std::to_string(want));
  };
  check("position_start", cal.slice.position_start, slice.position_start);
  check("quaternion_start", cal.slice.quaternion_start, slice.quaternion_start);
  if (cal.gripper) check("gripper.start", cal.gripper->start, finger_start(layout));
}

std::string_view protocol_name(CalibrationProtocol p) {
  switch (p) {
    case CalibrationProtocol::kManiSkillWalk: return "maniskill_walk";
    case CalibrationProtocol::kReferenceWalk: return "reference_walk";
    case CalibrationProtocol::kEpisodes: break;
  }
  return "episodes";
}

CalibrationProtocol parse_protocol(std::string_view name) {
  if (name == "maniskill_walk") return CalibrationProtocol::kManiSkillWalk;
  if (name == "reference_walk") return CalibrationProtocol::kReferenceWalk;
  if (name == "episodes") return CalibrationProtocol::kEpisodes;
  throw std::invalid_argument("unknown calibration protocol '" + std::string(name) + "' (known: maniskill_walk, reference_walk, episodes)");
}

adapt::ResponseCalibration calibrate(std::shared_ptr<const sim::EnvModel> model, const CalibrationOptions& o) {
  if (o.episodes < 1) throw std::invalid_argument("calibration needs at least one episode");
  if (o.steps < 2) throw std::invalid_argument("calibration needs at least two steps per episode");
  if (o.steps > 100000) throw std::invalid_argument("calibration steps must be at most 100000");
  const adapt::TcpSlice slice = tcp_slice(model->layout());
  const bool walk = o.protocol != CalibrationProtocol::kEpisodes;
  const bool autoreset = o.protocol == CalibrationProtocol::kManiSkillWalk;
  int steps = std::min(o.steps, model->horizon());
  if (walk) {
    // the reference's walks have no workspace box (ManiSkill has none): the same robot and profile,
    // with the workspace opened to the whole table; the open walk also raises the episode limit to
    // the walk length, the ManiSkill walk keeps the task's horizon and resets there
    sim::EnvConfig cfg = model->config();
    if (!autoreset) cfg.horizon = o.steps;
    cfg.workspace.lower = Eigen::Vector3d(-10.0, -10.0, -10.0);
    cfg.workspace.upper = Eigen::Vector3d(10.0, 10.0, 10.0);
    model = sim::EnvModel::make(model->task(), cfg, model->robot_ptr());
    steps = o.steps;
  }
  sim::Env env(model);
  std::vector<Pose6> commanded, observed;
  std::vector<double> grip_cmd, grip_obs;
  const int fs = o.gripper_channel ? finger_start(model->layout()) : -1;
  for (int e = 0; e < o.episodes; ++e) {
    Eigen::VectorXd prev = env.reset(derive_seed({o.seed, static_cast<std::uint64_t>(e)}));
    Rng rng(derive_seed({o.seed, static_cast<std::uint64_t>(e), 1}));
    std::uint64_t resets = 0;
    for (int t = 0; t < steps; ++t) {
      Action a;
      for (int c = 0; c < kActionDim; ++c) a[c] = rng.uniform(-1.0, 1.0);
      const sim::StepResult& r = env.step(a);
      if (r.safety != sim::SafetyFlag::kNone) break;
      // ManiSkill's vector wrapper returns the fresh episode's first observation on the step that
      // ends an episode: the sample of that step is the jump to it
      const bool reset_here = autoreset && r.truncated && t + 1 < steps;
      Eigen::VectorXd cur = reset_here
          ? env.reset(derive_seed({o.seed, static_cast<std::uint64_t>(e), 2, ++resets}))
          : r.obs;
      if (!walk || t > 0) {  // the reference records states after each step: no sample for step 0
        commanded.push_back(a.head<kPoseDim>());
        observed.push_back(adapt::tcp_response(prev, cur, slice));
        if (fs >= 0) {
          grip_cmd.push_back(a[kGripper]);
          grip_obs.push_back(0.5 * (cur[fs] + cur[fs + 1]) - 0.5 * (prev[fs] + prev[fs + 1]));
        }
      }
      prev = std::move(cur);
      if (!reset_here && r.episode_over()) break;
    }
  }
  adapt::ResponseCalibration c;
  c.task = std::string(sim::task_name(model->task()));
  c.slice = slice;
  c.fit = adapt::fit_linear_response(commanded, observed);
  c.episodes = o.episodes;
  c.steps = steps;
  c.seed = o.seed;
  c.rotation_mode = "live";
  c.profile = model->config().profile;
  c.protocol = std::string(protocol_name(o.protocol));
  if (fs >= 0) c.gripper = adapt::fit_gripper_response(grip_cmd, grip_obs, fs);
  return c;
}

}  // namespace actionshift::eval
