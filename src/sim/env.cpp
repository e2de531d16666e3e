// env model (shared, immutable) and env (per worker): reset, step, observations, safety checks
#include "actionshift/sim/env.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/rng.hpp"
#include "obs_noise.hpp"
#include "physics_world.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace actionshift::sim {

namespace detail {

struct ModelData {
  explicit ModelData(const RobotDescription& desc) : layout(desc) {}
  ArticulationLayout layout;
  std::array<int, 7> arm_bodies{};     // body index of each arm chain joint
  std::array<int, 2> finger_bodies{};  // left, right
};

struct EnvImpl {
  std::shared_ptr<const EnvModel> model;
  const ModelData* data{nullptr};
  std::unique_ptr<PhysicsWorld> world;
  std::vector<ObjectSpec> objects;
  StepResult last;
  EpisodeStats stats;
  bool started{false};
  // episode parameters
  Eigen::Vector3d goal{Eigen::Vector3d::Zero()};
  double peg_half_length{0.0}, peg_half_width{0.0}, hole_half_width{0.0};
  Eigen::Vector3d hole_offset{Eigen::Vector3d::Zero()};
  // scratch
  Eigen::VectorXd targets;
  Eigen::VectorXd obs_scratch;
  Rng obs_noise;  // this episode's observation-noise stream (EnvConfig::obs_noise)
};

}  // namespace detail

namespace {

void write_pose(Eigen::VectorXd& obs, int offset, const Eigen::Isometry3d& t) {
  obs.segment<3>(offset) = t.translation();
  obs.segment<4>(offset + 3) = matrix_to_quat_wxyz(t.linear());
}

}  // namespace

std::string_view safety_flag_name(SafetyFlag f) {
  const std::string_view n = kSafetyFlags.name(f);
  return n.empty() ? "unknown" : n;
}

SafetyFlag parse_safety_flag(std::string_view text, const std::string& source, const std::string& field) {
  return kSafetyFlags.parse(text, source, field);
}

// ---- profiles

std::vector<std::string> profile_names() {
  std::vector<std::string> out;
  for (const auto& e : kProfiles.entries) out.emplace_back(e.name);
  return out;
}

EnvConfig profile_config(std::string_view name) {
  EnvConfig c;
  const Profile p = parse_profile(name, "", "profile");
  c.profile = std::string(profile_name(p));
  switch (p) {
    case Profile::kManiskill: return c;  // the defaults
    case Profile::kIdeal:
      c.ik.mode = IkMode::kConverged;
      c.physics.arm_drive = ArmDrive::kVelocityServo;
      c.physics.arm_joint_limits = false;  // the converged ik keeps its targets inside the limits
      return c;
  }
  return c;
}

// ---- model

EnvModel::~EnvModel() = default;

std::shared_ptr<const EnvModel> EnvModel::make(TaskId task, const EnvConfig& config,
                                               std::shared_ptr<const RobotDescription> robot) {
  std::shared_ptr<EnvModel> m(new EnvModel());
  m->task_ = task;
  m->config_ = config;
  if (!(config.obs_noise >= 0.0 && config.obs_noise <= kMaxObsNoise))  // also rejects NaN
    throw std::invalid_argument("obs_noise must be a finite sigma in [0, 0.1] (metres / radians)");
  m->robot_ = robot ? std::move(robot) : std::shared_ptr<const RobotDescription>(&panda_description(), [](const RobotDescription*) {});
  const RobotDescription& desc = *m->robot_;
  m->arm_ = KinematicChain(desc, config.names.tcp_link);
  if (m->arm_.dof() != 7)
    throw std::invalid_argument("robot '" + desc.name + "': the chain to '" + config.names.tcp_link + "' has " +
                                std::to_string(m->arm_.dof()) + " movable joints, 7 expected");
  auto data = std::make_unique<detail::ModelData>(desc);
  for (int i = 0; i < 7; ++i) data->arm_bodies[static_cast<std::size_t>(i)] = data->layout.body_of_joint(m->arm_.joint_indices()[static_cast<std::size_t>(i)]);
  data->finger_bodies[0] = data->layout.body_of_joint(desc.joint_index(config.names.left_finger_joint));
  data->finger_bodies[1] = data->layout.body_of_joint(desc.joint_index(config.names.right_finger_joint));
  m->data_ = std::move(data);
  return m;
}

Eigen::Matrix<double, 9, 1> EnvModel::rest_qpos() const {
  constexpr double kPi = std::numbers::pi;
  const double j7 = task_description(task_).rest_wrist;
  Eigen::Matrix<double, 9, 1> q;
  q << 0.0, kPi / 8, 0.0, -5 * kPi / 8, 0.0, 3 * kPi / 4, j7, 0.04, 0.04;
  return q;
}

// ---- env

Env::Env(std::shared_ptr<const EnvModel> model) : impl_(std::make_unique<detail::EnvImpl>()) {
  if (!model) throw std::invalid_argument("Env needs a model");
  impl_->model = std::move(model);
  impl_->data = &impl_->model->data();
  const EnvModel& m = *impl_->model;
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = m.config().robot_base;
  impl_->world = std::make_unique<detail::PhysicsWorld>(
      m.robot(), impl_->data->layout, m.config().physics, base,
      std::vector<int>{impl_->data->finger_bodies[0], impl_->data->finger_bodies[1]});
  impl_->last.obs = Eigen::VectorXd::Zero(m.layout().size());
  impl_->obs_scratch = impl_->last.obs;
}

Env::~Env() = default;
Env::Env(Env&&) noexcept = default;
Env& Env::operator=(Env&&) noexcept = default;

const EnvModel& Env::model() const { return *impl_->model; }
const StepResult& Env::last() const { return impl_->last; }
const EpisodeStats& Env::episode() const { return impl_->stats; }

namespace {
// the state accessors read the Bullet world, which holds a robot only after the first reset
const detail::EnvImpl& require_started(const detail::EnvImpl& e, const char* what) {
  if (!e.started) throw std::logic_error(std::string("Env::") + what + " called before reset");
  return e;
}
}  // namespace

Eigen::Matrix<double, 9, 1> Env::qpos() const {
  require_started(*impl_, "qpos");
  const Eigen::VectorXd q = impl_->world->qpos();
  Eigen::Matrix<double, 9, 1> out;
  for (int i = 0; i < 7; ++i) out(i) = q(impl_->data->arm_bodies[static_cast<std::size_t>(i)]);
  out(7) = q(impl_->data->finger_bodies[0]);
  out(8) = q(impl_->data->finger_bodies[1]);
  return out;
}

Eigen::Isometry3d Env::tcp_pose_in_base() const {
  require_started(*impl_, "tcp_pose_in_base");
  return impl_->model->arm().fk(qpos().head<7>());
}

Eigen::Isometry3d Env::tcp_pose() const {
  require_started(*impl_, "tcp_pose");
  return impl_->world->base_pose() * tcp_pose_in_base();
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> Env::finger_forces() const {
  require_started(*impl_, "finger_forces");
  return {impl_->world->finger_contact_force(0, 0), impl_->world->finger_contact_force(1, 0)};
}

TaskSnapshot Env::snapshot() const {
  const detail::EnvImpl& e = require_started(*impl_, "snapshot");
  TaskSnapshot s;
  const Eigen::VectorXd q = e.world->qpos();
  const Eigen::VectorXd v = e.world->qvel();
  for (int i = 0; i < 7; ++i) {
    s.qpos(i) = q(e.data->arm_bodies[static_cast<std::size_t>(i)]);
    s.qvel(i) = v(e.data->arm_bodies[static_cast<std::size_t>(i)]);
  }
  for (int f = 0; f < 2; ++f) {
    s.qpos(7 + f) = q(e.data->finger_bodies[static_cast<std::size_t>(f)]);
    s.qvel(7 + f) = v(e.data->finger_bodies[static_cast<std::size_t>(f)]);
  }
  s.tcp = e.world->base_pose() * e.model->arm().fk(s.qpos.head<7>());
  const int nobj = static_cast<int>(std::min<std::size_t>(2, e.objects.size()));
  for (int i = 0; i < nobj; ++i) {
    s.obj[static_cast<std::size_t>(i)] = e.world->object_pose(i);
    s.obj_linvel[static_cast<std::size_t>(i)] = e.world->object_linear_velocity(i);
    s.obj_angvel[static_cast<std::size_t>(i)] = e.world->object_angular_velocity(i);
  }
  s.goal = e.goal;
  if (nobj > 0) {
    const Eigen::Vector3d fl = e.world->finger_contact_force(0, 0);
    const Eigen::Vector3d fr = e.world->finger_contact_force(1, 0);
    const Eigen::Vector3d y = s.tcp.linear().col(1);  // hand y axis (the tcp frame is the hand frame shifted)
    s.grasped = is_grasping(fl, fr, y, 0.5, 85.0);
    s.grasped_strict = is_grasping(fl, fr, y, 0.5, 20.0);
  }
  s.peg_half_length = e.peg_half_length;
  s.peg_half_width = e.peg_half_width;
  s.hole_half_width = e.hole_half_width;
  s.hole_offset = e.hole_offset;
  return s;
}

namespace {

// observation vector of a snapshot, in the task's layout
void compose_obs(TaskId task, const TaskSnapshot& s, Eigen::VectorXd& obs) {
  const ObservationLayout& l = observation_layout(task);
  obs.resize(l.size());
  obs.segment<9>(l.at("qpos").offset) = s.qpos;
  obs.segment<9>(l.at("qvel").offset) = s.qvel;
  write_pose(obs, l.at("tcp_pose").offset, s.tcp);
  task_description(task).observe(s, l, obs);
}

bool finite_snapshot(const TaskSnapshot& s) {
  bool ok = s.qpos.allFinite() && s.qvel.allFinite() && s.tcp.matrix().allFinite();
  for (int i = 0; i < 2; ++i)
    ok = ok && s.obj[static_cast<std::size_t>(i)].matrix().allFinite() && s.obj_linvel[static_cast<std::size_t>(i)].allFinite() &&
         s.obj_angvel[static_cast<std::size_t>(i)].allFinite();
  return ok;
}

// end the episode with a safety flag: nothing more is simulated, no success, no reward
const StepResult& end_episode(detail::EnvImpl& e, SafetyFlag f) {
  e.last.safety = f;
  e.last.success = false;
  e.last.terminated = false;
  e.last.reward = 0.0;
  e.stats.safety = f;
  e.stats.success_at_end = false;
  return e.last;
}

}  // namespace

const Eigen::VectorXd& Env::reset(std::uint64_t seed) {
  detail::EnvImpl& e = *impl_;
  const EnvModel& m = *e.model;
  Rng rng(seed);
  // robot: rest keyframe + N(0, 0.02) on all 9 entries, then fingers fully open
  Eigen::Matrix<double, 9, 1> q9 = m.rest_qpos();
  for (int i = 0; i < 9; ++i) q9(i) += rng.normal(0.0, 0.02);
  q9(7) = q9(8) = 0.04;
  // task objects (facts section 1)
  e.objects.clear();
  TaskEpisode episode;
  task_description(m.task()).spawn(rng, episode);
  for (const TaskObject& o : episode.objects) {
    detail::ObjectSpec spec;
    for (const TaskBox& b : o.boxes) {
      detail::BoxPart part;
      part.half_extents = b.half_extents;
      part.pose = Eigen::Isometry3d::Identity();
      part.pose.translation() = b.offset;
      spec.boxes.push_back(part);
    }
    spec.mass = o.mass;
    spec.position = o.position;
    spec.orientation = o.orientation;
    e.objects.push_back(std::move(spec));
  }
  e.goal = episode.goal;
  e.peg_half_length = episode.peg_half_length;
  e.peg_half_width = episode.peg_half_width;
  e.hole_half_width = episode.hole_half_width;
  e.hole_offset = episode.hole_offset;
  // fresh physics world at the sampled state
  const int nb = e.world->num_dofs();
  Eigen::VectorXd qb = Eigen::VectorXd::Zero(nb);
  for (int i = 0; i < 7; ++i) qb(e.data->arm_bodies[static_cast<std::size_t>(i)]) = q9(i);
  qb(e.data->finger_bodies[0]) = q9(7);
  qb(e.data->finger_bodies[1]) = q9(8);
  e.world->rebuild(e.objects, qb);
  e.targets = qb;

  e.stats = EpisodeStats{};
  e.started = true;
  e.last = StepResult{};
  const TaskSnapshot s = snapshot();
  compose_obs(m.task(), s, e.last.obs);
  e.obs_noise = Rng(derive_seed({seed, detail::kObsNoiseStream}));
  detail::apply_obs_noise(m.layout(), m.config().obs_noise, e.obs_noise, e.last.obs);
  const TaskEvaluation ev = evaluate_task(m.task(), s);
  e.last.success = ev.success;
  e.last.reward = ev.reward;
  return e.last.obs;
}

const StepResult& Env::step(const Action& canonical) {
  return step(std::span<const double>(canonical.data(), static_cast<std::size_t>(canonical.size())));
}

const StepResult& Env::step(std::span<const double> a) {
  detail::EnvImpl& e = *impl_;
  const EnvModel& m = *e.model;
  if (!e.started) throw std::logic_error("Env::step called before reset");
  if (e.last.episode_over()) return e.last;

  // fail closed on the action before anything is simulated
  auto end_with = [&](SafetyFlag f) -> const StepResult& { return end_episode(e, f); };
  if (a.size() != static_cast<std::size_t>(kActionDim)) return end_with(SafetyFlag::kBadActionShape);
  for (double v : a)
    if (!std::isfinite(v)) return end_with(SafetyFlag::kNonfiniteAction);
  for (double v : a)
    if (std::abs(v) > m.config().max_action_magnitude) return end_with(SafetyFlag::kActionOutOfRange);

  // controller: pose delta -> target pose -> ik -> joint targets; gripper -> finger targets
  Eigen::Matrix<double, 6, 1> pose;
  for (int i = 0; i < 6; ++i) pose(i) = a[static_cast<std::size_t>(i)];
  const PoseCommand cmd = interpret_pose_command(pose);
  const double g = a[6];
  if (cmd.clipped || std::abs(g) > 1.0) ++e.stats.clipped_steps;
  const Eigen::VectorXd qb = e.world->qpos();
  ChainVector q_arm(7);
  for (int i = 0; i < 7; ++i) q_arm(i) = qb(e.data->arm_bodies[static_cast<std::size_t>(i)]);
  const Eigen::Isometry3d tcp = m.arm().fk(q_arm);
  const IkResult ik = m.config().ik.mode == IkMode::kSingleStep ? single_step_ik(m.arm(), q_arm, cmd, m.config().ik)
                                                                  : solve_ik(m.arm(), q_arm, target_pose(tcp, cmd), m.config().ik);
  for (int i = 0; i < 7; ++i) e.targets(e.data->arm_bodies[static_cast<std::size_t>(i)]) = ik.q(i);
  e.targets(e.data->finger_bodies[0]) = finger_target(g);
  e.targets(e.data->finger_bodies[1]) = finger_target(g);
  e.world->set_targets(e.targets);
  e.world->step_control();
  ++e.last.elapsed_steps;
  ++e.stats.steps;

  // state checks: a bad state never reaches the observation
  const TaskSnapshot s = snapshot();
  if (!finite_snapshot(s)) return end_with(SafetyFlag::kNonfiniteState);
  bool unstable = s.qvel.cwiseAbs().maxCoeff() > m.config().max_joint_speed;
  for (std::size_t i = 0; i < std::min<std::size_t>(2, e.objects.size()); ++i)
    unstable = unstable || s.obj_linvel[i].norm() > m.config().max_object_speed;
  if (unstable) return end_with(SafetyFlag::kUnstableState);

  compose_obs(m.task(), s, e.last.obs);
  detail::apply_obs_noise(m.layout(), m.config().obs_noise, e.obs_noise, e.last.obs);
  const TaskEvaluation ev = evaluate_task(m.task(), s);
  e.last.success = ev.success;
  e.last.terminated = ev.success;
  e.last.reward = ev.reward;
  e.last.truncated = e.last.elapsed_steps >= m.horizon();
  e.stats.episode_return += ev.reward;
  e.stats.success_once = e.stats.success_once || ev.success;
  e.stats.success_at_end = ev.success;
  if (!m.config().workspace.contains(s.tcp.translation())) {
    e.last.safety = SafetyFlag::kWorkspaceViolation;
    e.stats.safety = SafetyFlag::kWorkspaceViolation;
    e.stats.success_at_end = false;
  }
  return e.last;
}

const StepResult& Env::abort(SafetyFlag flag) {
  detail::EnvImpl& e = *impl_;
  if (!e.started) throw std::logic_error("Env::abort called before reset");
  if (e.last.episode_over() || flag == SafetyFlag::kNone) return e.last;
  return end_episode(e, flag);
}

void check_horizon(long long horizon, const std::string& source, const std::string& field) {
  if (horizon < 0 || horizon > kMaxHorizon)
    throw InputError(source, field, "must be 0 (the task's) or 1 to " + std::to_string(kMaxHorizon) + " control steps (got " +
                                        std::to_string(horizon) + ")");
}

}  // namespace actionshift::sim
