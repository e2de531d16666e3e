// env model (shared, immutable) and env (per worker): reset, step, observations, safety checks
#include "actionshift/sim/env.hpp"

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

constexpr double kPi = std::numbers::pi;
constexpr double kCubeHalf = 0.02;
constexpr double kDensity = 1000.0;  // sapien default [kg/m^3]

Eigen::Quaterniond yaw_quat(double yaw) { return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())); }

detail::ObjectSpec cube_spec(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  detail::ObjectSpec s;
  s.boxes.push_back({Eigen::Vector3d::Constant(kCubeHalf), Eigen::Isometry3d::Identity()});
  s.mass = kDensity * 8.0 * kCubeHalf * kCubeHalf * kCubeHalf;
  s.position = p;
  s.orientation = q;
  return s;
}

void write_pose(Eigen::VectorXd& obs, int offset, const Eigen::Isometry3d& t) {
  obs.segment<3>(offset) = t.translation();
  obs.segment<4>(offset + 3) = matrix_to_quat_wxyz(t.linear());
}

}  // namespace

std::string_view safety_flag_name(SafetyFlag f) {
  switch (f) {
    case SafetyFlag::kNone: return "none";
    case SafetyFlag::kBadActionShape: return "bad_action_shape";
    case SafetyFlag::kNonfiniteAction: return "nonfinite_action";
    case SafetyFlag::kActionOutOfRange: return "action_out_of_range";
    case SafetyFlag::kWorkspaceViolation: return "workspace_violation";
    case SafetyFlag::kNonfiniteState: return "nonfinite_state";
    case SafetyFlag::kUnstableState: return "unstable_state";
  }
  return "unknown";
}

// ---- profiles

std::vector<std::string> profile_names() { return {"maniskill", "ideal"}; }

EnvConfig profile_config(std::string_view name) {
  EnvConfig c;
  c.profile = std::string(name);
  if (name == "maniskill") return c;  // the defaults
  if (name == "ideal") {
    c.ik.mode = IkMode::kConverged;
    c.physics.arm_drive = ArmDrive::kVelocityServo;
    c.physics.arm_joint_limits = false;  // the converged ik keeps its targets inside the limits
    return c;
  }
  throw std::invalid_argument("unknown fidelity profile '" + std::string(name) + "' (known: maniskill, ideal)");
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
  const double j7 = (task_ == TaskId::kStackCube || task_ == TaskId::kPegInsertionSide) ? -kPi / 4 : kPi / 4;
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
void compose_obs(TaskId task, const TaskSnapshot& s, const detail::EnvImpl& e, Eigen::VectorXd& obs) {
  const ObservationLayout& l = observation_layout(task);
  obs.resize(l.size());
  obs.segment<9>(l.at("qpos").offset) = s.qpos;
  obs.segment<9>(l.at("qvel").offset) = s.qvel;
  write_pose(obs, l.at("tcp_pose").offset, s.tcp);
  const Eigen::Vector3d tcp = s.tcp.translation();
  switch (task) {
    case TaskId::kPickCube:
      obs(l.at("is_grasped").offset) = s.grasped ? 1.0 : 0.0;
      obs.segment<3>(l.at("goal_pos").offset) = s.goal;
      write_pose(obs, l.at("obj_pose").offset, s.obj[0]);
      obs.segment<3>(l.at("tcp_to_obj_pos").offset) = s.obj[0].translation() - tcp;
      obs.segment<3>(l.at("obj_to_goal_pos").offset) = s.goal - s.obj[0].translation();
      break;
    case TaskId::kPushCube:
    case TaskId::kPullCube:
      obs.segment<3>(l.at("goal_pos").offset) = s.goal;
      write_pose(obs, l.at("obj_pose").offset, s.obj[0]);
      break;
    case TaskId::kStackCube:
      write_pose(obs, l.at("cubeA_pose").offset, s.obj[0]);
      write_pose(obs, l.at("cubeB_pose").offset, s.obj[1]);
      obs.segment<3>(l.at("tcp_to_cubeA_pos").offset) = s.obj[0].translation() - tcp;
      obs.segment<3>(l.at("tcp_to_cubeB_pos").offset) = s.obj[1].translation() - tcp;
      obs.segment<3>(l.at("cubeA_to_cubeB_pos").offset) = s.obj[1].translation() - s.obj[0].translation();
      break;
    case TaskId::kPegInsertionSide: {
      write_pose(obs, l.at("peg_pose").offset, s.obj[0]);
      obs.segment<3>(l.at("peg_half_size").offset) = Eigen::Vector3d(e.peg_half_length, e.peg_half_width, e.peg_half_width);
      Eigen::Isometry3d hole = s.obj[1];
      hole.translate(e.hole_offset);
      write_pose(obs, l.at("box_hole_pose").offset, hole);
      obs(l.at("box_hole_radius").offset) = e.hole_half_width;
      break;
    }
  }
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
  e.goal.setZero();
  e.peg_half_length = e.peg_half_width = e.hole_half_width = 0.0;
  e.hole_offset.setZero();
  switch (m.task()) {
    case TaskId::kPickCube: {
      const double x = rng.uniform(-0.1, 0.1), y = rng.uniform(-0.1, 0.1);
      const double yaw = rng.uniform(0.0, 2 * kPi);
      e.objects.push_back(cube_spec(Eigen::Vector3d(x, y, kCubeHalf), yaw_quat(yaw)));
      const double gx = rng.uniform(-0.1, 0.1), gy = rng.uniform(-0.1, 0.1);
      e.goal = Eigen::Vector3d(gx, gy, kCubeHalf + rng.uniform(0.0, 0.3));
      break;
    }
    case TaskId::kPushCube:
    case TaskId::kPullCube: {
      const double x = rng.uniform(-0.1, 0.1), y = rng.uniform(-0.1, 0.1);
      e.objects.push_back(cube_spec(Eigen::Vector3d(x, y, kCubeHalf), Eigen::Quaterniond::Identity()));
      const double dx = m.task() == TaskId::kPushCube ? 0.2 : -0.2;
      e.goal = Eigen::Vector3d(x + dx, y, 1e-3);
      break;
    }
    case TaskId::kStackCube: {
      const double ox = rng.uniform(-0.1, 0.1), oy = rng.uniform(-0.1, 0.1);
      const double ax = rng.uniform(-0.1, 0.1), ay = rng.uniform(-0.2, 0.2);
      const double min_sep = 2.0 * (std::sqrt(2.0) * kCubeHalf + 0.001);
      double bx = 0.0, by = 0.0;
      bool placed = false;
      for (int tries = 0; tries < 100 && !placed; ++tries) {
        bx = rng.uniform(-0.1, 0.1);
        by = rng.uniform(-0.2, 0.2);
        placed = std::hypot(bx - ax, by - ay) > min_sep;
      }
      if (!placed) bx = by = 0.0;  // ManiSkill's sampler quirk
      const double yaw_a = rng.uniform(0.0, 2 * kPi), yaw_b = rng.uniform(0.0, 2 * kPi);
      e.objects.push_back(cube_spec(Eigen::Vector3d(ox + ax, oy + ay, kCubeHalf), yaw_quat(yaw_a)));
      e.objects.push_back(cube_spec(Eigen::Vector3d(ox + bx, oy + by, kCubeHalf), yaw_quat(yaw_b)));
      break;
    }
    case TaskId::kPegInsertionSide: {
      const double L = rng.uniform(0.085, 0.125);
      const double r = rng.uniform(0.015, 0.025);
      const double clearance = 0.003;
      const double cy = 0.5 * (L - r) * rng.uniform(-1.0, 1.0);
      const double cz = 0.5 * (L - r) * rng.uniform(-1.0, 1.0);
      e.peg_half_length = L;
      e.peg_half_width = r;
      e.hole_half_width = r + clearance;
      e.hole_offset = Eigen::Vector3d(0.0, cy, cz);
      const double px = rng.uniform(-0.1, 0.1), py = rng.uniform(-0.3, 0.0);
      const double pyaw = rng.uniform(kPi / 2 - kPi / 3, kPi / 2 + kPi / 3);
      const double bx = rng.uniform(-0.05, 0.05), by = rng.uniform(0.2, 0.4);
      const double byaw = rng.uniform(kPi / 2 - kPi / 8, kPi / 2 + kPi / 8);
      detail::ObjectSpec peg;
      peg.boxes.push_back({Eigen::Vector3d(L, r, r), Eigen::Isometry3d::Identity()});
      peg.mass = kDensity * 8.0 * L * r * r;
      peg.position = Eigen::Vector3d(px, py, r);
      peg.orientation = yaw_quat(pyaw);
      e.objects.push_back(peg);
      // box with a hole along its x axis: four static boxes (ManiSkill's _build_box_with_hole)
      detail::ObjectSpec box;
      const double inner = r + clearance, outer = L, depth = L;
      const double thick = 0.5 * (outer - inner);
      const double h0 = 0.5 * cy, h1 = 0.5 * cz;
      const double off = thick + inner;
      auto part = [](double hx, double hy, double hz, double x, double y, double z) {
        detail::BoxPart p;
        p.half_extents = Eigen::Vector3d(hx, hy, hz);
        p.pose = Eigen::Isometry3d::Identity();
        p.pose.translation() = Eigen::Vector3d(x, y, z);
        return p;
      };
      box.boxes.push_back(part(depth, thick - h0, outer, 0, off + h0, 0));
      box.boxes.push_back(part(depth, thick + h0, outer, 0, -off + h0, 0));
      box.boxes.push_back(part(depth, outer, thick - h1, 0, 0, off + h1));
      box.boxes.push_back(part(depth, outer, thick + h1, 0, 0, -off + h1));
      box.mass = 0.0;
      box.position = Eigen::Vector3d(bx, by, L);
      box.orientation = yaw_quat(byaw);
      e.objects.push_back(box);
      break;
    }
  }
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
  compose_obs(m.task(), s, e, e.last.obs);
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

  compose_obs(m.task(), s, e, e.last.obs);
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

}  // namespace actionshift::sim
