// scripted experts: state feedback on the observation only (no simulator access)
#include "actionshift/policy/expert.hpp"

#include "actionshift/core/hash.hpp"
#include "actionshift/policy/detail/motion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace actionshift::policy {
namespace {

using detail::cube_grasp_rotation;
using detail::move_to;
using detail::yaw_of;
using sim::TaskId;

constexpr double kCubeHalf = sim::kCubeHalfSize;  // [m] every cube task
constexpr double kGraspYawTolerance = 0.4;               // [rad] closing on a cube this far off its faces still works
constexpr double kRestYaw = 0.0;                         // hand yaw of the rest pose (pick, push, pull)
constexpr double kStackRestYaw = std::numbers::pi / 2;  // stack: joint 7 = -pi/4 turns the hand a quarter

// offsets of the fields an expert reads, resolved once per task
struct Fields {
  int qpos{0}, qvel{0}, tcp{0}, obj{0}, goal{-1}, grasped{-1}, obj_b{-1};
};

Fields fields_of(TaskId task) {
  const sim::TaskDescription& d = sim::task_description(task);
  const sim::ObservationLayout& l = d.layout();
  auto offset = [&](std::string_view name) { return name.empty() ? -1 : l.at(name).offset; };
  Fields f;
  f.qpos = l.at("qpos").offset;
  f.qvel = l.at("qvel").offset;
  f.tcp = l.at("tcp_pose").offset;
  f.obj = offset(d.roles.object);
  f.goal = offset(d.roles.goal);
  f.grasped = offset(d.roles.grasped);
  f.obj_b = offset(d.roles.object_b);
  return f;
}

const Fields& fields(TaskId task) {
  static const std::vector<Fields> all = [] {
    std::vector<Fields> v;
    for (TaskId t : sim::all_tasks()) v.push_back(fields_of(t));
    return v;
  }();
  return all.at(static_cast<std::size_t>(task));
}

// finger opening [m]: 0.08 fully open, about 0.04 on a cube, about 0 closed on nothing
double finger_opening(const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f) {
  return obs(f.qpos + 7) + obs(f.qpos + 8);
}

// grasp a cube at `cube` (pose) with the hand pointing down; returns true in `holding` when the
// cube is between closed fingers. `grasped_hint` < 0: infer from finger opening and distance.
Action grasp_cube(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& cube, double opening, double grasped_hint,
                  double ref_yaw, bool& holding) {
  const Eigen::Vector3d c = cube.translation();
  const Eigen::Matrix3d r = cube_grasp_rotation(ref_yaw, cube.linear());
  const Eigen::Vector3d to = c - tcp.translation();
  const double xy_err = to.head<2>().norm();
  const double yaw_err = std::abs(std::remainder(yaw_of(r) - yaw_of(tcp.linear()), 2 * std::numbers::pi));
  const bool near = to.norm() < 0.012;
  holding = grasped_hint >= 0.0 ? grasped_hint > 0.5 : (near && opening > 0.025 && opening < 0.055);
  if (holding) return move_to(tcp, tcp.translation(), detail::down_rotation(yaw_of(tcp.linear())), -1.0);
  // closing on the cube: keep closing while the fingers move in
  if (near && opening < 0.075 && opening > 0.025) return move_to(tcp, c, r, -1.0);
  // fingers closed on nothing: open again where we are (lifting a little)
  if (opening <= 0.025) return move_to(tcp, tcp.translation() + Eigen::Vector3d(0, 0, 0.01), r, 1.0);
  // above the cube and aligned: descend; otherwise approach from above
  if (xy_err < 0.008 && yaw_err < kGraspYawTolerance) {
    if (near) return move_to(tcp, c, r, -1.0);
    return move_to(tcp, c, r, 1.0);
  }
  // hover above the cube while turning; once over it, come down as the yaw error shrinks
  // (continuous in the yaw error, so a learner does not stall at a hover height)
  const double lower = std::clamp((yaw_err - kGraspYawTolerance) / 0.3, 0.0, 1.0);
  const double hover = c.z() + (xy_err > 0.03 ? 0.06 : 0.005 + 0.025 * lower);
  const double z = xy_err > 0.03 ? std::max(hover, std::min(tcp.translation().z(), hover + 0.05)) : hover;
  const Eigen::Vector3d above(c.x(), c.y(), z);
  return move_to(tcp, above, r, 1.0);
}

Action pick_action(const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f) {
  const Eigen::Isometry3d tcp = ObservationView::pose(obs, f.tcp);
  const Eigen::Isometry3d cube = ObservationView::pose(obs, f.obj);
  const Eigen::Vector3d goal = obs.segment<3>(f.goal);
  bool holding = false;
  Action a = grasp_cube(tcp, cube, finger_opening(obs, f), obs(f.grasped), kRestYaw, holding);
  if (!holding) return a;
  // carry: move the tcp so that the cube lands on the goal, keep the grip
  const Eigen::Vector3d target = tcp.translation() + (goal - cube.translation());
  return move_to(tcp, target, detail::down_rotation(yaw_of(tcp.linear())), -1.0);
}

// push (+x) or pull (-x) the cube along x with closed fingers, from its far side
Action push_pull_action(const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f, double dir) {
  const Eigen::Isometry3d tcp = ObservationView::pose(obs, f.tcp);
  const Eigen::Vector3d p = tcp.translation();
  const Eigen::Vector3d cube = obs.segment<3>(f.obj);
  const Eigen::Vector3d goal = obs.segment<3>(f.goal);
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  // contact line: tcp 0.035 m behind the cube centre (cube half 0.02 + finger pad)
  const double behind_x = cube.x() - dir * (kCubeHalf + 0.017);
  const double along = dir * (p.x() - cube.x());  // < 0: behind the cube
  const double lateral = p.y() - cube.y();
  const double work_z = 0.02;
  const double travel_z = 0.075;
  const bool behind = along < -(kCubeHalf + 0.008);
  if (behind && std::abs(lateral) < 0.012 && p.z() < work_z + 0.015) {
    // in contact position: drive the cube to (a little past) the goal centre, correct y
    const double remaining = dir * (goal.x() - cube.x()) + 0.03;
    const Eigen::Vector3d target(p.x() + dir * std::clamp(remaining, 0.0, 0.04), cube.y(), work_z);
    return move_to(tcp, target, down, -1.0, 2.0, 0.6);
  }
  // get to the pre-contact point from above, never crossing the cube low
  const Eigen::Vector3d pre(behind_x - dir * 0.02, cube.y(), work_z);
  if (behind && std::abs(lateral) < 0.012) return move_to(tcp, Eigen::Vector3d(pre.x(), pre.y(), work_z), down, -1.0);
  const double xy_err = (p.head<2>() - pre.head<2>()).norm();
  if (xy_err > 0.015) {
    if (p.z() < travel_z - 0.02 && (along > -(kCubeHalf + 0.03) && std::abs(lateral) < 0.05))
      return move_to(tcp, Eigen::Vector3d(p.x(), p.y(), travel_z), down, -1.0);  // rise clear of the cube first
    return move_to(tcp, Eigen::Vector3d(pre.x(), pre.y(), std::max(travel_z, std::min(p.z(), 0.15))), down, -1.0);
  }
  return move_to(tcp, pre, down, -1.0);
}

Action stack_action(const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f) {
  const Eigen::Isometry3d tcp = ObservationView::pose(obs, f.tcp);
  const Eigen::Isometry3d a = ObservationView::pose(obs, f.obj);
  const Eigen::Isometry3d b = ObservationView::pose(obs, f.obj_b);
  const double opening = finger_opening(obs, f);
  const Eigen::Vector3d off = a.translation() - b.translation();
  const bool on_top = off.head<2>().norm() < 0.012 && std::abs(off.z() - 2 * kCubeHalf) < 0.006;
  const Eigen::Matrix3d r = cube_grasp_rotation(kStackRestYaw, a.linear());
  // placed: let go and back off upwards
  if (on_top) {
    const double clear = (tcp.translation() - a.translation()).norm();
    if (opening < 0.075 && clear < 0.03) return move_to(tcp, tcp.translation(), r, 1.0);
    return move_to(tcp, a.translation() + Eigen::Vector3d(0, 0, 0.08), r, 1.0);
  }
  bool holding = false;
  Action act = grasp_cube(tcp, a, opening, -1.0, kStackRestYaw, holding);
  if (!holding) {
    // near cube B with A on the table beside it: nothing special, grasp_cube approaches from above
    return act;
  }
  // carry A above B, then lower it onto B
  const Eigen::Vector3d grip = tcp.translation() - a.translation();  // keep the grip offset
  const Eigen::Vector3d b_top = b.translation() + Eigen::Vector3d(0, 0, 2 * kCubeHalf);
  const double xy_err = (a.translation().head<2>() - b_top.head<2>()).norm();
  Eigen::Vector3d a_target;
  if (xy_err > 0.02 && a.translation().z() < b_top.z() + 0.02)
    a_target = Eigen::Vector3d(a.translation().x(), a.translation().y(), b_top.z() + 0.035);  // lift clear of B first
  else if (xy_err > 0.006)
    a_target = Eigen::Vector3d(b_top.x(), b_top.y(), b_top.z() + (xy_err > 0.02 ? 0.035 : 0.015));
  else
    a_target = b_top + Eigen::Vector3d(0, 0, 0.002);
  return move_to(tcp, a_target + grip, detail::down_rotation(yaw_of(tcp.linear())), -1.0);
}

// peg insertion (attempt): grasp the peg behind its centre, lift, align it with the hole axis,
// go to a pre-insertion point on the hole axis, push in
Action peg_action(const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f) {
  const sim::ObservationLayout& l = sim::observation_layout(TaskId::kPegInsertionSide);
  const Eigen::Isometry3d tcp = ObservationView::pose(obs, f.tcp);
  const Eigen::Isometry3d peg = ObservationView::pose(obs, f.obj);
  const Eigen::Isometry3d hole = ObservationView::pose(obs, f.obj_b);
  const double half_len = obs(l.at("peg_half_size").offset);
  const double opening = finger_opening(obs, f);
  // grasp point 0.04 m behind the peg centre along its axis; hand down, fingers across the peg
  const Eigen::Vector3d axis = peg.linear().col(0);
  const Eigen::Vector3d grasp_pt = peg.translation() - 0.5 * half_len * axis;
  const double peg_yaw = std::atan2(axis.y(), axis.x());
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  // hand x along the peg axis so the fingers (hand y) close across it
  const double hand_yaw_now = yaw_of(tcp.linear());
  const double yaw = hand_yaw_now + std::remainder(peg_yaw - hand_yaw_now, std::numbers::pi);
  const Eigen::Matrix3d r_grasp = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * down;
  const Eigen::Vector3d to = grasp_pt - tcp.translation();
  const double width = 2.0 * obs(l.at("peg_half_size").offset + 1);
  const bool near = to.norm() < 0.012;
  const bool holding = near && opening > width - 0.01 && opening < width + 0.012;
  const bool lifted = peg.translation().z() > 0.05;
  if (!holding && !lifted) {
    if (near && opening < 0.075 && opening > width - 0.01) return move_to(tcp, grasp_pt, r_grasp, -1.0);
    if (opening <= width - 0.01) return move_to(tcp, tcp.translation() + Eigen::Vector3d(0, 0, 0.01), r_grasp, 1.0);
    const double xy = to.head<2>().norm();
    if (xy < 0.008) return move_to(tcp, grasp_pt, r_grasp, near ? -1.0 : 1.0);
    return move_to(tcp, Eigen::Vector3d(grasp_pt.x(), grasp_pt.y(), grasp_pt.z() + 0.06), r_grasp, 1.0);
  }
  // holding: rotate the hand so the peg axis matches the hole axis (+x of the hole frame points
  // out of the box towards the approach side; the peg head must enter along it)
  const Eigen::Vector3d hole_axis = hole.linear().col(0);
  const Eigen::Matrix3d peg_to_tcp = peg.linear().transpose() * tcp.linear();
  // desired peg frame: x = hole x, z up as close as possible
  Eigen::Matrix3d peg_des;
  {
    const Eigen::Vector3d x = hole_axis.normalized();
    Eigen::Vector3d z = Eigen::Vector3d::UnitZ() - x * x.z();
    z.normalize();
    peg_des.col(0) = x;
    peg_des.col(2) = z;
    peg_des.col(1) = z.cross(x);
  }
  const Eigen::Matrix3d tcp_des = peg_des * peg_to_tcp;
  const Eigen::Vector3d head = peg * Eigen::Vector3d(half_len, 0, 0);
  const Eigen::Vector3d tcp_minus_head = tcp.translation() - head;
  // pre-insertion: head on the hole axis, 0.05 m in front of the hole opening
  const Eigen::Vector3d pre = hole.translation() - 0.05 * hole_axis;
  const Eigen::Vector3d head_rel = hole.inverse() * head;
  const double off_axis = head_rel.tail<2>().norm();
  const double rot_err = sim::so3_log(tcp_des * tcp.linear().transpose()).norm();
  Eigen::Vector3d head_target;
  if (rot_err > 0.05 || off_axis > 0.004 || head_rel.x() < -0.06)
    head_target = pre;
  else
    head_target = hole.translation() + 0.02 * hole_axis;
  return move_to(tcp, head_target + tcp_minus_head, tcp_des, -1.0, 2.0, 0.5);
}

// the scripted expert of each task that has one
struct ExpertEntry {
  TaskId task;
  Action (*act)(const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f);
};
constexpr ExpertEntry kExperts[] = {
    {TaskId::kPickCube, &pick_action},
    {TaskId::kPushCube, [](const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f) { return push_pull_action(obs, f, +1.0); }},
    {TaskId::kPullCube, [](const Eigen::Ref<const Eigen::VectorXd>& obs, const Fields& f) { return push_pull_action(obs, f, -1.0); }},
    {TaskId::kStackCube, &stack_action},
    {TaskId::kPegInsertionSide, &peg_action},
};

const ExpertEntry& expert_of(TaskId task) {
  for (const ExpertEntry& e : kExperts)
    if (e.task == task) return e;
  throw std::invalid_argument("no scripted expert for task " + std::string(sim::task_name(task)));
}

class ExpertPolicy final : public Policy {
 public:
  explicit ExpertPolicy(TaskId task) : task_(task), hash_(sha256_hex(expert_identity(task))) {}
  void reset() override {}
  Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) override { return expert_action(task_, obs); }
  std::string name() const override { return "expert"; }
  std::string sha256() const override { return hash_; }
  TaskId task() const override { return task_; }
  std::unique_ptr<Policy> clone() const override { return std::make_unique<ExpertPolicy>(task_); }

 private:
  TaskId task_;
  std::string hash_;
};

}  // namespace

std::string expert_identity(TaskId task) {
  return std::string(kExpertVersion) + "/" + std::string(sim::task_name(task));
}

Action expert_action(TaskId task, const Eigen::Ref<const Eigen::VectorXd>& obs) {
  check_observation(obs, task);
  return expert_of(task).act(obs, fields(task));
}

std::unique_ptr<Policy> make_expert(TaskId task) {
  (void)expert_of(task);  // a task without a scripted expert is refused here, not at its first step
  return std::make_unique<ExpertPolicy>(task);
}

}  // namespace actionshift::policy
