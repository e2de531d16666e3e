// HDF5 logs of the audit: a ManiSkill-layout file (with its JSON sidecar) and a robomimic-layout file
// are written, read back and audited; bad files get one-line errors naming the dataset.
#include "actionshift/core/error.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "actionshift/selftest/audit_hdf5.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace actionshift::selftest {
namespace {

using ::testing::HasSubstr;

adapt::ResponseModel model() {
  return adapt::ResponseModel{{0.03, 0.03, 0.03, 0.05, 0.05, 0.05}, {0.003, 0.003, 0.003, 0.004, 0.004, 0.004}};
}

std::string tmp(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("actionshift_audit_h5_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

TEST(AuditHdf5, ManiSkillLayoutIsReadAndAudited) {
  Conventions truth;
  truth.contract = reference::representative_contracts("seen")[1];
  truth.rotation = RotationRep::kEulerXyz;  // what pd_ee_delta_pose declares; the test's rotations are too small to tell
  const ActionLog log = synthetic_log(truth, model(), {});
  const std::string path = tmp("trajectory.h5");
  write_log_maniskill(log, path, "pd_ee_delta_pose");
  const ActionLog back = read_log(path);
  EXPECT_EQ(back.layout, "maniskill");
  ASSERT_EQ(back.episodes.size(), log.episodes.size());
  EXPECT_EQ(back.transitions(), log.transitions());
  // float32 datasets, as ManiSkill writes them
  EXPECT_NEAR(back.episodes[1].actions[3][2], log.episodes[1].actions[3][2], 1e-6);
  ASSERT_TRUE(back.declared.has_value());
  EXPECT_EQ(back.declared->rotation, RotationRep::kEulerXyz);
  EXPECT_EQ(back.declared_from, "control_mode pd_ee_delta_pose");
  ASSERT_TRUE(back.episodes[0].poses[0].fingers.has_value());
  AuditOptions o;
  o.declared = *back.declared;
  o.model = model();
  const AuditResult r = audit(back, o);
  ASSERT_EQ(r.status, Status::kMismatch) << to_text(r);
  // every field but scale, which is the log's measured gain (a band is claimed, never a grid value)
  EXPECT_EQ(r.identified.contract.permutation(), truth.contract.permutation());
  EXPECT_EQ(r.identified.contract.sign(), truth.contract.sign());
  EXPECT_EQ(r.identified.contract.target(), truth.contract.target());
  EXPECT_EQ(r.identified.contract.lag(), truth.contract.lag());
  EXPECT_THAT(r.reason, HasSubstr("channels 0 and 5 SWAPPED"));
}

TEST(AuditHdf5, RobomimicLayoutIsReadAndAudited) {
  // robosuite's OSC_POSE: delta, base, axis-angle, gripper -1 opens (inverted in the canonical convention)
  Conventions truth;
  auto f = Contract::identity().fields();
  f.gripper_inverted = true;
  truth.contract = Contract::make(f);
  const ActionLog log = synthetic_log(truth, model(), {});
  const std::string path = tmp("demo.hdf5");
  write_log_robomimic(log, path, "OSC_POSE");
  const ActionLog back = read_log(path);
  EXPECT_EQ(back.layout, "robomimic");
  EXPECT_EQ(back.transitions(), log.transitions());  // next_obs carries the final pose
  EXPECT_EQ(back.episodes[2].poses[5].quaternion, log.episodes[2].poses[5].quaternion);  // x y z w converted
  EXPECT_EQ(*back.episodes[2].poses[5].fingers, *log.episodes[2].poses[5].fingers);
  ASSERT_TRUE(back.declared.has_value());
  EXPECT_TRUE(back.declared->contract.gripper_inverted());
  AuditOptions o;
  o.declared = *back.declared;
  o.model = model();
  const AuditResult r = audit(back, o);
  EXPECT_EQ(r.status, Status::kPass) << to_text(r);
  // declared the canonical polarity instead: the fingers tell
  o.declared = Conventions{};
  const AuditResult m = audit(back, o);
  ASSERT_EQ(m.status, Status::kMismatch) << to_text(m);
  EXPECT_THAT(m.reason, HasSubstr("gripper polarity differs"));
}

void expect_error(const std::string& path, const std::string& message) {
  try {
    read_log(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path + ": " + message);
  }
}

TEST(AuditHdf5, BadFilesNameTheDataset) {
  const std::string not_h5 = tmp("text.h5");
  std::ofstream(not_h5) << "hello";
  expect_error(not_h5, "not an HDF5 file");

  ActionLog log = synthetic_log(Conventions{}, model(), {});
  log.episodes[1].actions[4][2] = std::numeric_limits<double>::quiet_NaN();
  const std::string nan = tmp("nan.h5");
  write_log_maniskill(log, nan, "pd_ee_delta_pose");
  expect_error(nan, "traj_1/actions: row 4 column 2: not a finite number");

  const std::string joint = tmp("joint.h5");
  write_log_maniskill(synthetic_log(Conventions{}, model(), {}), joint, "pd_joint_delta_pos");
  try {
    read_log(joint);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("joint.json: control_mode: 'pd_joint_delta_pos' is joint-space"));
  }

  ActionLog short_log = synthetic_log(Conventions{}, model(), {});
  short_log.episodes[0].poses.resize(10);
  const std::string rows = tmp("rows.h5");
  write_log_robomimic(short_log, rows, "OSC_POSE");
  expect_error(rows, "data/demo_0/obs: robot0_eef_pos/robot0_eef_quat rows differ from the 50 actions");
}

}  // namespace
}  // namespace actionshift::selftest
