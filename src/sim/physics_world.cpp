// bullet world: the panda multibody built by hand from a RobotDescription, the table, task objects
#include "physics_world.hpp"

#include "actionshift/sim/task.hpp"

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyGearConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointLimitConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointMotor.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace actionshift::sim::detail {
namespace {

btVector3 bt(const Eigen::Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }
Eigen::Vector3d eig(const btVector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); }
btQuaternion bt_quat(const Eigen::Matrix3d& r) {
  const Eigen::Quaterniond q(r);
  return btQuaternion(q.x(), q.y(), q.z(), q.w());
}
btTransform bt(const Eigen::Isometry3d& t) { return btTransform(bt_quat(t.linear()), bt(t.translation())); }
Eigen::Isometry3d eig(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  out.translation() = eig(t.getOrigin());
  return out;
}


// collision groups
constexpr int kGroupStatic = btBroadphaseProxy::StaticFilter;
constexpr int kGroupDefault = btBroadphaseProxy::DefaultFilter;
constexpr int kMaskAll = btBroadphaseProxy::AllFilter;

// largest number of driven (non-finger) joints the implicit drive's fixed-capacity solve handles
constexpr int kMaxArmDofs = 16;
// largest number of movable bodies (arm and fingers) the inertia computation's fixed-capacity scratch handles
constexpr int kMaxDofs = 32;

thread_local BulletInputRecorder* t_recorder = nullptr;

}  // namespace

void set_thread_input_recorder(BulletInputRecorder* r) { t_recorder = r; }

// ---- articulation layout

ArticulationLayout::ArticulationLayout(const RobotDescription& desc) {
  const std::size_t nl = desc.links.size();
  link_body.assign(nl, {-1, Eigen::Isometry3d::Identity()});
  std::vector<int> joint_body(desc.joints.size(), -1);
  // links are in depth-first order, so a parent's body is known before its children
  for (std::size_t l = 0; l < nl; ++l) {
    if (static_cast<int>(l) == desc.root) continue;
    const int j = desc.parent_joint(static_cast<int>(l));
    if (j < 0) throw std::invalid_argument("robot '" + desc.name + "': link '" + desc.links[l].name + "' is not connected to the root");
    const JointDescription& jd = desc.joints[static_cast<std::size_t>(j)];
    const auto& parent = link_body[static_cast<std::size_t>(jd.parent)];
    if (!jd.movable()) {
      link_body[l] = {parent.first, parent.second * jd.origin};
      continue;
    }
    Body b;
    b.parent = parent.first;
    b.joint = j;
    b.prismatic = jd.type == JointDescription::Type::kPrismatic;
    b.joint_in_parent_link = parent.second * jd.origin;
    b.axis = jd.axis;
    b.link_name = desc.links[l].name;
    joint_body[static_cast<std::size_t>(j)] = static_cast<int>(bodies.size());
    link_body[l] = {static_cast<int>(bodies.size()), Eigen::Isometry3d::Identity()};
    bodies.push_back(std::move(b));
  }
  base.link_name = desc.links[static_cast<std::size_t>(desc.root)].name;
  // merge inertia and shapes of every link into its body (urdf frame of the body)
  struct Acc { double m{0}; Eigen::Vector3d mc{Eigen::Vector3d::Zero()}; std::vector<std::tuple<double, Eigen::Vector3d, Eigen::Matrix3d>> parts; };
  std::vector<Acc> acc(bodies.size() + 1);
  for (std::size_t l = 0; l < nl; ++l) {
    const auto& [bi, t] = link_body[l];
    Body& body = bi < 0 ? base : bodies[static_cast<std::size_t>(bi)];
    const LinkDescription& ld = desc.links[l];
    for (const auto& g : ld.collisions) body.shapes.emplace_back(g, t * g.origin);
    if (ld.inertial.mass <= 0.0) continue;
    Acc& a = acc[static_cast<std::size_t>(bi + 1)];
    const Eigen::Vector3d c = t * ld.inertial.com;
    a.m += ld.inertial.mass;
    a.mc += ld.inertial.mass * c;
    a.parts.emplace_back(ld.inertial.mass, c, t.linear() * ld.inertial.inertia * t.linear().transpose());
  }
  for (std::size_t i = 0; i < acc.size(); ++i) {
    Body& body = i == 0 ? base : bodies[i - 1];
    const Acc& a = acc[i];
    Eigen::Vector3d com = Eigen::Vector3d::Zero();
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    double mass = a.m;
    if (mass > 0.0) {
      com = a.mc / mass;
      for (const auto& [m, c, in] : a.parts) {
        const Eigen::Vector3d r = c - com;
        inertia += in + m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      }
    } else {
      // a massless movable link (e.g. a frame-only link): Bullet needs a positive mass, so it gets
      // 1 g and a matching small inertia, negligible against the Panda's 0.015-4.97 kg links
      mass = 1e-3;
      inertia = 1e-7 * Eigen::Matrix3d::Identity();
    }
    body.mass = mass;
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    const bool diagonal = std::abs(inertia(0, 1)) + std::abs(inertia(0, 2)) + std::abs(inertia(1, 2)) == 0.0;
    if (diagonal) {
      body.inertia_diag = inertia.diagonal();
    } else {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(inertia);
      axes = es.eigenvectors();
      if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
      body.inertia_diag = es.eigenvalues();
    }
    body.link_to_bullet.setIdentity();
    body.link_to_bullet.linear() = axes;
    body.link_to_bullet.translation() = com;
  }
  mimic_of.assign(bodies.size(), -1);
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const auto& jd = desc.joints[static_cast<std::size_t>(bodies[b].joint)];
    if (jd.mimic_joint) {
      const int mj = desc.joint_index(*jd.mimic_joint);
      mimic_of[b] = joint_body[static_cast<std::size_t>(mj)];
    }
  }
}

int ArticulationLayout::body_of_joint(int joint) const {
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (bodies[b].joint == joint) return static_cast<int>(b);
  return -1;
}

// ---- world

namespace {
std::unique_ptr<btCollisionShape> make_shape(const CollisionGeometry& g) {
  switch (g.type) {
    case CollisionGeometry::Type::kBox:
      return std::make_unique<btBoxShape>(bt(0.5 * g.size));
    case CollisionGeometry::Type::kSphere:
      return std::make_unique<btSphereShape>(g.size.x());
    case CollisionGeometry::Type::kCylinder:
      return std::make_unique<btCylinderShapeZ>(btVector3(g.size.x(), g.size.x(), 0.5 * g.size.y()));
    case CollisionGeometry::Type::kMesh: {
      auto hull = std::make_unique<btConvexHullShape>();
      for (const auto& v : g.mesh->vertices) hull->addPoint(bt(v), false);
      hull->recalcLocalAabb();
      hull->optimizeConvexHull();
      hull->setMargin(0.001);
      return hull;
    }
  }
  return nullptr;
}
}  // namespace

PhysicsWorld::PhysicsWorld(const RobotDescription& desc, const ArticulationLayout& layout, const PhysicsConfig& cfg,
                           const Eigen::Isometry3d& base_pose, std::vector<int> finger_bodies)
    : desc_(desc), layout_(layout), cfg_(cfg), base_pose_(base_pose), finger_bodies_(std::move(finger_bodies)) {
  h_ = cfg_.control_dt_s / (cfg_.sim_steps_per_control * cfg_.substeps_per_sim_step);
  auto build_compound = [&](const ArticulationLayout::Body& body) -> btCompoundShape* {
    if (body.shapes.empty()) return nullptr;
    auto compound = std::make_unique<btCompoundShape>(true, static_cast<int>(body.shapes.size()));
    const Eigen::Isometry3d inv = body.link_to_bullet.inverse();
    for (const auto& [g, pose] : body.shapes) {
      auto child = make_shape(g);
      compound->addChildShape(bt(inv * pose), child.get());
      shapes_.push_back(std::move(child));
    }
    btCompoundShape* raw = compound.get();
    shapes_.push_back(std::move(compound));
    return raw;
  };
  base_shape_ = build_compound(layout_.base);
  for (const auto& b : layout_.bodies) body_shapes_.push_back(build_compound(b));
  table_shape_ = std::make_unique<btBoxShape>(btVector3(kTable.half_x, kTable.half_y, kTable.half_z));
  q_target_ = Eigen::VectorXd::Zero(num_dofs());
  for (int i = 0; i < num_dofs(); ++i)
    if (!is_finger(i)) arm_dofs_.push_back(i);
  if (num_dofs() > kMaxDofs)
    throw std::invalid_argument("robot '" + desc.name + "': " + std::to_string(num_dofs()) + " movable joints, at most " +
                                std::to_string(kMaxDofs) + " supported");
  if (static_cast<int>(arm_dofs_.size()) > kMaxArmDofs)
    throw std::invalid_argument("robot '" + desc.name + "': " + std::to_string(arm_dofs_.size()) + " driven joints, at most " +
                                std::to_string(kMaxArmDofs) + " supported");
  mass_ = Eigen::MatrixXd::Zero(num_dofs(), num_dofs());
}

void PhysicsWorld::detach_all() {
  if (!world_) return;
    for (auto& c : constraints_) world_->removeMultiBodyConstraint(c.get());
    for (auto& o : objects_) world_->removeRigidBody(o.get());
    if (table_) world_->removeRigidBody(table_.get());
    for (auto& c : colliders_) world_->removeCollisionObject(c.get());
    if (robot_) world_->removeMultiBody(robot_.get());
}

PhysicsWorld::~PhysicsWorld() {
  // remove everything from the world before the pieces are destroyed
  detach_all();
}

void PhysicsWorld::rebuild(const std::vector<ObjectSpec>& objects, const Eigen::VectorXd& qpos) {
  // tear down in dependency order
  detach_all();
  constraints_.clear();
  motors_.clear();
  objects_.clear();
  object_shapes_.clear();
  colliders_.clear();
  table_.reset();
  robot_.reset();
  world_.reset();
  solver_.reset();
  broadphase_.reset();
  dispatcher_.reset();
  collision_config_.reset();

  // small pools: a fresh configuration per episode must be cheap (the default pools are ~4 MB)
  btDefaultCollisionConstructionInfo cci;
  cci.m_defaultMaxPersistentManifoldPoolSize = 64;
  cci.m_defaultMaxCollisionAlgorithmPoolSize = 64;
  collision_config_ = std::make_unique<btDefaultCollisionConfiguration>(cci);
  dispatcher_ = std::make_unique<btCollisionDispatcher>(collision_config_.get());
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  solver_ = std::make_unique<btMultiBodyConstraintSolver>();
  world_ = std::make_unique<btMultiBodyDynamicsWorld>(dispatcher_.get(), broadphase_.get(), solver_.get(),
                                                       collision_config_.get());
  world_->setGravity(btVector3(0, 0, -cfg_.gravity));
  world_->getSolverInfo().m_numIterations = cfg_.solver_iterations;

  // table: static box, top at z = 0
  {
    btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, table_shape_.get());
    info.m_startWorldTransform.setIdentity();
    info.m_startWorldTransform.setOrigin(btVector3(kTable.center_x, 0, -kTable.half_z));
    info.m_friction = cfg_.default_friction;
    info.m_restitution = 0.0;
    table_ = std::make_unique<btRigidBody>(info);
    table_->setContactProcessingThreshold(cfg_.contact_processing_threshold);
    world_->addRigidBody(table_.get(), kGroupStatic, kMaskAll ^ kGroupStatic);
  }

  build_robot(qpos);

  // task objects
  for (const ObjectSpec& spec : objects) {
    auto compound = std::make_unique<btCompoundShape>(true, static_cast<int>(spec.boxes.size()));
    for (const BoxPart& p : spec.boxes) {
      auto box = std::make_unique<btBoxShape>(bt(p.half_extents));
      compound->addChildShape(bt(p.pose), box.get());
      object_shapes_.push_back(std::move(box));
    }
    btVector3 inertia(0, 0, 0);
    if (spec.mass > 0.0) {
      // single box: exact box inertia about its centre (all objects here are single boxes when dynamic)
      const Eigen::Vector3d e = 2.0 * spec.boxes.front().half_extents;
      inertia = btVector3(spec.mass / 12.0 * (e.y() * e.y() + e.z() * e.z()), spec.mass / 12.0 * (e.x() * e.x() + e.z() * e.z()),
                          spec.mass / 12.0 * (e.x() * e.x() + e.y() * e.y()));
    }
    btRigidBody::btRigidBodyConstructionInfo info(spec.mass, nullptr, compound.get(), inertia);
    info.m_startWorldTransform = btTransform(
        btQuaternion(spec.orientation.x(), spec.orientation.y(), spec.orientation.z(), spec.orientation.w()), bt(spec.position));
    info.m_friction = cfg_.default_friction;
    info.m_restitution = 0.0;
    auto body = std::make_unique<btRigidBody>(info);
    body->setActivationState(DISABLE_DEACTIVATION);
    body->setContactProcessingThreshold(cfg_.contact_processing_threshold);
    if (cfg_.friction_anchors) body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_HAS_FRICTION_ANCHOR);
    if (spec.mass > 0.0)
      world_->addRigidBody(body.get(), kGroupDefault, kMaskAll);
    else
      world_->addRigidBody(body.get(), kGroupStatic, kMaskAll ^ kGroupStatic);
    object_shapes_.push_back(std::move(compound));
    objects_.push_back(std::move(body));
  }
  finger_forces_.assign(finger_bodies_.size() * objects_.size(), Eigen::Vector3d::Zero());
  q_target_ = qpos;
  if (t_recorder != nullptr) t_recorder->world = this;
}

void PhysicsWorld::build_robot(const Eigen::VectorXd& qpos) {
  const int n = num_dofs();
  robot_ = std::make_unique<btMultiBody>(n, 0.0, btVector3(0, 0, 0), true, false);
  const Eigen::Isometry3d base_bullet = base_pose_ * layout_.base.link_to_bullet;
  robot_->setBaseWorldTransform(bt(base_bullet));
  for (int i = 0; i < n; ++i) {
    const auto& b = layout_.bodies[static_cast<std::size_t>(i)];
    const auto& parent = b.parent < 0 ? layout_.base : layout_.bodies[static_cast<std::size_t>(b.parent)];
    // joint frame J in the parent bullet frame P
    const Eigen::Isometry3d j_in_p = parent.link_to_bullet.inverse() * b.joint_in_parent_link;
    const Eigen::Matrix3d r_pc = j_in_p.linear() * b.link_to_bullet.linear();
    const btQuaternion rot_parent_to_this = bt_quat(r_pc.transpose());
    const Eigen::Vector3d axis_c = b.link_to_bullet.linear().transpose() * b.axis;
    const Eigen::Vector3d e = j_in_p.translation();
    const Eigen::Vector3d d = b.link_to_bullet.linear().transpose() * b.link_to_bullet.translation();
    if (b.prismatic)
      robot_->setupPrismatic(i, b.mass, bt(b.inertia_diag), b.parent, rot_parent_to_this, bt(axis_c), bt(e), bt(d), true);
    else
      robot_->setupRevolute(i, b.mass, bt(b.inertia_diag), b.parent, rot_parent_to_this, bt(axis_c), bt(e), bt(d), true);
  }
  robot_->finalizeMultiDof();
  robot_->setHasSelfCollision(false);
  robot_->setLinearDamping(0.0);
  robot_->setAngularDamping(0.0);
  robot_->setUseGyroTerm(true);
  for (int i = 0; i < n; ++i) {
    robot_->setJointPos(i, qpos(i));
    robot_->setJointVel(i, 0.0);
  }
  world_->addMultiBody(robot_.get());

  btAlignedObjectArray<btQuaternion> w2l;
  btAlignedObjectArray<btVector3> lo;
  robot_->forwardKinematics(w2l, lo);

  // colliders
  if (base_shape_ != nullptr) {
    auto col = std::make_unique<btMultiBodyLinkCollider>(robot_.get(), -1);
    col->setCollisionShape(base_shape_);
    col->setWorldTransform(bt(base_bullet));
    col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_STATIC_OBJECT);
    col->setFriction(cfg_.default_friction);
    world_->addCollisionObject(col.get(), kGroupStatic, kMaskAll ^ kGroupStatic);
    robot_->setBaseCollider(col.get());
    colliders_.push_back(std::move(col));
  }
  for (int i = 0; i < n; ++i) {
    btCompoundShape* shape = body_shapes_[static_cast<std::size_t>(i)];
    if (shape == nullptr) continue;
    auto col = std::make_unique<btMultiBodyLinkCollider>(robot_.get(), i);
    col->setCollisionShape(shape);
    const bool finger = std::find(finger_bodies_.begin(), finger_bodies_.end(), i) != finger_bodies_.end();
    col->setFriction(finger ? cfg_.finger_friction : cfg_.default_friction);
    col->setRestitution(0.0);
    col->setContactProcessingThreshold(cfg_.contact_processing_threshold);
    if (finger && cfg_.friction_anchors) col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_HAS_FRICTION_ANCHOR);
    world_->addCollisionObject(col.get(), kGroupDefault, kMaskAll);
    robot_->getLink(i).m_collider = col.get();
    colliders_.push_back(std::move(col));
  }
  robot_->updateCollisionObjectWorldTransforms(w2l, lo);

  // drives, limits and mimic coupling
  for (int i = 0; i < n; ++i) {
    const auto& b = layout_.bodies[static_cast<std::size_t>(i)];
    const bool finger = is_finger(i);
    const double limit = finger ? cfg_.finger_force_limit : cfg_.arm_force_limit;
    if (finger || cfg_.arm_drive == ArmDrive::kVelocityServo) {
      auto motor = std::make_unique<btMultiBodyJointMotor>(robot_.get(), i, 0, 0.0, limit * h_);
      motor->setPositionTarget(0.0, 0.0);
      motor->setVelocityTarget(0.0, 1.0);
      motors_.push_back(motor.get());
      world_->addMultiBodyConstraint(motor.get());
      constraints_.push_back(std::move(motor));
    } else {
      motors_.push_back(nullptr);  // driven by apply_implicit_pd
    }
    const auto& jd = desc_.joints[static_cast<std::size_t>(b.joint)];
    if ((finger || cfg_.arm_joint_limits) && std::isfinite(jd.lower) && std::isfinite(jd.upper)) {
      auto lim = std::make_unique<btMultiBodyJointLimitConstraint>(robot_.get(), i, jd.lower, jd.upper);
      world_->addMultiBodyConstraint(lim.get());
      constraints_.push_back(std::move(lim));
    }
  }
  if (cfg_.finger_gear) {
    for (int i = 0; i < n; ++i) {
      const int m = layout_.mimic_of[static_cast<std::size_t>(i)];
      if (m < 0) continue;
      const auto& jd = desc_.joints[static_cast<std::size_t>(layout_.bodies[static_cast<std::size_t>(i)].joint)];
      // constraint row: v_a + ratio * v_b = 0, so ratio = -1 / multiplier gives q_i = multiplier * q_m.
      // bullet only corrects the position drift of a gear for one sign of the error (the other sign goes
      // to the split-impulse channel, which multibody dofs ignore), so the pair is coupled twice, once
      // in each direction
      for (int dir = 0; dir < 2; ++dir) {
        const int a = dir == 0 ? m : i;
        const int b = dir == 0 ? i : m;
        const double ratio = dir == 0 ? -1.0 / jd.mimic_multiplier : -jd.mimic_multiplier;
        auto gear = std::make_unique<btMultiBodyGearConstraint>(robot_.get(), a, robot_.get(), b, btVector3(0, 0, 0),
                                                                btVector3(0, 0, 0), btMatrix3x3::getIdentity(),
                                                                btMatrix3x3::getIdentity());
        gear->setGearRatio(ratio);
        gear->setRelativePositionTarget(dir == 0 ? jd.mimic_offset / jd.mimic_multiplier : -jd.mimic_offset);
        gear->setErp(0.1);
        gear->setMaxAppliedImpulse(cfg_.finger_force_limit * h_);
        world_->addMultiBodyConstraint(gear.get());
        constraints_.push_back(std::move(gear));
      }
    }
  }
}

void PhysicsWorld::step_control() {
  const int n = num_dofs();
  const double k_over_d = cfg_.drive_stiffness / cfg_.drive_damping;
  const btVector3 g = world_->getGravity();
  const int steps = cfg_.sim_steps_per_control * cfg_.substeps_per_sim_step;
  BulletInputRecorder* rec = t_recorder != nullptr && t_recorder->recording ? t_recorder : nullptr;
  for (int s = 0; s < steps; ++s) {
    std::size_t row = 0;
    if (rec) {
      row = rec->inputs.size();
      rec->inputs.resize(row + 3 * static_cast<std::size_t>(n), 0.0);
    }
    if (cfg_.arm_drive == ArmDrive::kImplicitPd) apply_implicit_pd(rec ? rec->inputs.data() + row : nullptr);
    for (int i = 0; i < n; ++i) {
      const double q = robot_->getJointPos(i);
      const double err = q_target_(i) - q;
      btMultiBodyJointMotor* motor = motors_[static_cast<std::size_t>(i)];
      // overdamped pd (K, D) reduced to its dominant first-order mode: v* = (K/D)(q* - q)
      if (motor != nullptr) {
        motor->setVelocityTarget(k_over_d * err, 1.0);
        if (rec) rec->inputs[row + 3 * static_cast<std::size_t>(i) + 1] = k_over_d * err;
      }
      if (is_finger(i)) {
        // a blocked pd drive pushes with K*|q*-q|: cap the motor at that (and at the force limit)
        const double f = std::min(cfg_.finger_force_limit, cfg_.drive_stiffness * std::abs(err));
        motor->setMaxAppliedImpulse(f * h_);
        if (rec) rec->inputs[row + 3 * static_cast<std::size_t>(i) + 2] = f * h_;
      }
      // exact gravity compensation: cancels the m*g the world applies to every link
      if (cfg_.gravity_compensation) robot_->addLinkForce(i, -g * robot_->getLinkMass(i));
    }
    world_->stepSimulation(h_, 0, h_);
  }
  compute_contact_forces();
}

void PhysicsWorld::replay_control(const double* inputs) {
  const int n = num_dofs();
  const btVector3 g = world_->getGravity();
  const int steps = cfg_.sim_steps_per_control * cfg_.substeps_per_sim_step;
  for (int s = 0; s < steps; ++s, inputs += 3 * n) {
    for (int i = 0; i < n; ++i) {
      const double* in = inputs + 3 * i;
      btMultiBodyJointMotor* motor = motors_[static_cast<std::size_t>(i)];
      if (motor == nullptr) {
        if (cfg_.arm_drive == ArmDrive::kImplicitPd) robot_->addJointTorque(i, in[0]);
      } else {
        motor->setVelocityTarget(in[1], 1.0);
        if (is_finger(i)) motor->setMaxAppliedImpulse(in[2]);
      }
      if (cfg_.gravity_compensation) robot_->addLinkForce(i, -g * robot_->getLinkMass(i));
    }
    world_->stepSimulation(h_, 0, h_);
  }
}

bool PhysicsWorld::is_finger(int body) const {
  return std::find(finger_bodies_.begin(), finger_bodies_.end(), body) != finger_bodies_.end();
}

void PhysicsWorld::compute_mass_matrix() {
  // M = sum over bodies of m Jv^T Jv + Jw^T (R I R^T) Jw, with the geometric jacobians of each body's
  // centre of mass built from bullet's own kinematics of the current state (world frame)
  const int n = num_dofs();
  // every joint's world axis and pivot once: each body's jacobian uses those of all its ancestors,
  // and each Bullet query walks the chain to the base (the same calls, so the same values, as
  // querying them again for every descendant)
  Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxDofs> axis(3, n), pivot(3, n);
  for (int j = 0; j < n; ++j) {
    const btMultibodyLink& lj = robot_->getLink(j);
    if (lj.m_jointType == btMultibodyLink::eRevolute) {
      axis.col(j) = eig(robot_->localDirToWorld(j, lj.getAxisTop(0)));
      pivot.col(j) = eig(robot_->localPosToWorld(j, -lj.m_dVector));
    } else if (lj.m_jointType == btMultibodyLink::ePrismatic) {
      axis.col(j) = eig(robot_->localDirToWorld(j, lj.getAxisBottom(0)));
    }
  }
  // Each body adds m Jv^T Jv + Jw^T (R I R^T) Jw, whose entries are nonzero only between the joints
  // that move it (its ancestors). The sums are formed term by term in the order Eigen's dynamic-size
  // products used here before (inner index 0, 1, 2; the mass as the product's scale factor; Jw^T I
  // first), so M is the same bit for bit, without the general matrix-product kernels and their
  // temporaries on 9 x 9 zero-padded operands.
  mass_.setZero();
  std::array<int, kMaxDofs> anc{};
  std::array<Eigen::Vector3d, kMaxDofs> jv, jw, jwi;
  for (int i = 0; i < n; ++i) {
    const btMultibodyLink& link = robot_->getLink(i);
    const Eigen::Vector3d com = eig(robot_->localPosToWorld(i, btVector3(0, 0, 0)));
    const btMatrix3x3 basis = robot_->localFrameToWorld(i, btMatrix3x3::getIdentity());
    Eigen::Matrix3d r;
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) r(a, c) = basis[a][c];
    const Eigen::Vector3d inertia_local = eig(link.m_inertiaLocal);
    int na = 0;
    for (int j = i; j >= 0; j = robot_->getLink(j).m_parent) {
      const btMultibodyLink& lj = robot_->getLink(j);
      const auto k = static_cast<std::size_t>(na);
      anc[k] = j;
      jv[k].setZero();
      jw[k].setZero();
      if (lj.m_jointType == btMultibodyLink::eRevolute) {
        const Eigen::Vector3d a = axis.col(j);
        jv[k] = a.cross(com - pivot.col(j));
        jw[k] = a;
      } else if (lj.m_jointType == btMultibodyLink::ePrismatic) {
        jv[k] = axis.col(j);
      }
      ++na;
    }
    const Eigen::Matrix3d inertia_world = r * inertia_local.asDiagonal() * r.transpose();
    const double m = link.m_mass;
    for (int x = 0; x < na; ++x) {  // (Jw^T I) row of joint x
      const auto xi = static_cast<std::size_t>(x);
      for (int c = 0; c < 3; ++c)
        jwi[xi][c] = jw[xi][0] * inertia_world(0, c) + jw[xi][1] * inertia_world(1, c) + jw[xi][2] * inertia_world(2, c);
    }
    for (int x = 0; x < na; ++x) {
      const auto xi = static_cast<std::size_t>(x);
      for (int y = 0; y < na; ++y) {
        const auto yi = static_cast<std::size_t>(y);
        double lin = jv[xi][0] * jv[yi][0];
        lin += jv[xi][1] * jv[yi][1];
        lin += jv[xi][2] * jv[yi][2];
        double ang = jwi[xi][0] * jw[yi][0];
        ang += jwi[xi][1] * jw[yi][1];
        ang += jwi[xi][2] * jw[yi][2];
        double& e = mass_(anc[xi], anc[yi]);
        e += lin * m;
        e += ang;
      }
    }
  }
}

void PhysicsWorld::apply_implicit_pd(double* record) {
  // PhysX-style implicit PD drive on the arm joints. With tau = K (q* - q - h v') - D v' and
  // v' = v + h M^-1 tau over one step h, the end-of-step velocity solves
  //   (M + h (h K + D) I) v' = M v + h K (q* - q)
  // (the arm block of the joint-space inertia M; gravity is compensated, Coriolis terms are left to
  // bullet). The resulting torque is clipped to the drive's force limit and applied for the step, so
  // the link inertia carries motion from one control step into the next as it does in ManiSkill.
  compute_mass_matrix();
  const int na = static_cast<int>(arm_dofs_.size());
  if (na == 0) return;
  const double k = cfg_.drive_stiffness, d = cfg_.drive_damping;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxArmDofs, kMaxArmDofs> a(na, na);
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxArmDofs, 1> v(na), err(na);
  for (int r = 0; r < na; ++r) {
    const int br = arm_dofs_[static_cast<std::size_t>(r)];
    v(r) = robot_->getJointVel(br);
    err(r) = q_target_(br) - robot_->getJointPos(br);
    for (int c = 0; c < na; ++c) a(r, c) = mass_(br, arm_dofs_[static_cast<std::size_t>(c)]);
  }
  const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxArmDofs, 1> rhs = a * v + h_ * k * err;
  a.diagonal().array() += h_ * (h_ * k + d);
  const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxArmDofs, 1> v_next = a.ldlt().solve(rhs);
  for (int r = 0; r < na; ++r) {
    const double tau = std::clamp(k * err(r) - (h_ * k + d) * v_next(r), -cfg_.arm_force_limit, cfg_.arm_force_limit);
    robot_->addJointTorque(arm_dofs_[static_cast<std::size_t>(r)], tau);
    if (record) record[3 * static_cast<std::size_t>(arm_dofs_[static_cast<std::size_t>(r)])] = tau;
  }
}

void PhysicsWorld::compute_contact_forces() {
  std::fill(finger_forces_.begin(), finger_forces_.end(), Eigen::Vector3d::Zero());
  if (objects_.empty()) return;
  const int nm = dispatcher_->getNumManifolds();
  for (int m = 0; m < nm; ++m) {
    const btPersistentManifold* pm = dispatcher_->getManifoldByIndexInternal(m);
    const btCollisionObject* a = pm->getBody0();
    const btCollisionObject* b = pm->getBody1();
    for (std::size_t f = 0; f < finger_bodies_.size(); ++f) {
      const btMultiBodyLinkCollider* fc = robot_->getLink(finger_bodies_[f]).m_collider;
      double sign = 0.0;
      const btCollisionObject* other = nullptr;
      if (a == fc) { sign = 1.0; other = b; }
      else if (b == fc) { sign = -1.0; other = a; }
      else continue;
      for (std::size_t o = 0; o < objects_.size(); ++o) {
        if (other != objects_[o].get()) continue;
        Eigen::Vector3d total = Eigen::Vector3d::Zero();
        for (int c = 0; c < pm->getNumContacts(); ++c) {
          const btManifoldPoint& pt = pm->getContactPoint(c);
          // impulse on body0 is +normal (normalWorldOnB points from B to A)
          total += eig(pt.m_normalWorldOnB) * pt.m_appliedImpulse + eig(pt.m_lateralFrictionDir1) * pt.m_appliedImpulseLateral1 +
                   eig(pt.m_lateralFrictionDir2) * pt.m_appliedImpulseLateral2;
        }
        finger_forces_[f * objects_.size() + o] += sign * total / h_;
      }
    }
  }
}

Eigen::VectorXd PhysicsWorld::qpos() const {
  Eigen::VectorXd q(num_dofs());
  for (int i = 0; i < num_dofs(); ++i) q(i) = robot_->getJointPos(i);
  return q;
}

Eigen::VectorXd PhysicsWorld::qvel() const {
  Eigen::VectorXd v(num_dofs());
  for (int i = 0; i < num_dofs(); ++i) v(i) = robot_->getJointVel(i);
  return v;
}

Eigen::Isometry3d PhysicsWorld::object_pose(int i) const {
  return eig(objects_[static_cast<std::size_t>(i)]->getWorldTransform());
}
Eigen::Vector3d PhysicsWorld::object_linear_velocity(int i) const {
  return eig(objects_[static_cast<std::size_t>(i)]->getLinearVelocity());
}
Eigen::Vector3d PhysicsWorld::object_angular_velocity(int i) const {
  return eig(objects_[static_cast<std::size_t>(i)]->getAngularVelocity());
}
Eigen::Vector3d PhysicsWorld::finger_contact_force(int finger_slot, int object) const {
  return finger_forces_[static_cast<std::size_t>(finger_slot) * objects_.size() + static_cast<std::size_t>(object)];
}
Eigen::Isometry3d PhysicsWorld::body_urdf_pose(int body) const {
  // bullet's own kinematics of the current state (not the eigen chain): link frame -> world
  const btVector3 origin = robot_->localPosToWorld(body, btVector3(0, 0, 0));
  const btMatrix3x3 basis = robot_->localFrameToWorld(body, btMatrix3x3::getIdentity());
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) t.linear()(r, c) = basis[r][c];
  t.translation() = eig(origin);
  return t * layout_.bodies[static_cast<std::size_t>(body)].link_to_bullet.inverse();
}

}  // namespace actionshift::sim::detail
