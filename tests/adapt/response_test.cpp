#include "actionshift/adapt/calibration.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/transforms.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace actionshift::adapt {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

Eigen::Vector4d wxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

TEST(Quaternion, RotvecRoundTripAndRelativeRotation) {
  Rng rng(3);
  for (int k = 0; k < 100; ++k) {
    const Vec3 rv(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(rv.norm(), rv.normalized()));
    EXPECT_LT((quat_to_rotvec(wxyz(q)) - rv).norm(), 1e-12);
    EXPECT_LT((quat_to_rotvec(-wxyz(q)) - rv).norm(), 1e-12);  // double cover
  }
  // Hamilton product agrees with Eigen's
  const Eigen::Quaterniond a(0.3, -0.2, 0.9, 0.1), b(-0.5, 0.4, 0.2, 0.7);
  EXPECT_LT((quat_multiply(wxyz(a.normalized()), wxyz(b.normalized())) - wxyz(a.normalized() * b.normalized())).norm(), 1e-12);
}

TEST(TcpResponse, TranslationAndRotationVector) {
  // a layout with the position at offset 4 and the quaternion at 7 (the reference implementation's calibration test uses offset 4)
  std::vector<double> prev(12, 0.0), cur(12, 0.0);
  prev[4] = 0.1, prev[5] = 0.2, prev[6] = 0.3;
  cur[4] = 0.15, cur[5] = 0.2, cur[6] = 0.25;
  const Eigen::Quaterniond q0(Eigen::AngleAxisd(0.4, Vec3::UnitX()));
  const Eigen::Quaterniond dq(Eigen::AngleAxisd(0.05, Vec3::UnitZ()));
  const Eigen::Vector4d a = wxyz(q0), b = wxyz(dq * q0);
  for (int i = 0; i < 4; ++i) prev[static_cast<std::size_t>(7 + i)] = a[i], cur[static_cast<std::size_t>(7 + i)] = b[i];
  const Pose6 r = tcp_response(prev, cur, {4, 7});
  EXPECT_NEAR(r[0], 0.05, 1e-15);
  EXPECT_NEAR(r[2], -0.05, 1e-15);
  EXPECT_LT((r.tail<3>() - Vec3(0, 0, 0.05)).norm(), 1e-12);  // world-frame rotation about z
  EXPECT_TRUE(tcp_rotation(cur, {4, 7}).isApprox((dq * q0).toRotationMatrix(), 1e-12));
  EXPECT_THAT([&] { tcp_response(prev, cur, {10, 7}); }, ThrowsMessage<std::invalid_argument>(HasSubstr("does not fit")));
}

TEST(FitLinearResponse, RecoversSignedGainsNoiseAndR2) {
  Rng rng(11);
  const std::array<double, 6> alpha{0.08, 0.05, 0.09, -0.04, 0.07, 0.1};
  std::vector<Pose6> x, y;
  for (int i = 0; i < 20000; ++i) {
    Pose6 c, r;
    for (int k = 0; k < 6; ++k) {
      c[k] = rng.uniform(-1, 1);
      r[k] = alpha[static_cast<std::size_t>(k)] * c[k] + 0.005 * rng.normal();
    }
    x.push_back(c);
    y.push_back(r);
  }
  const LinearFit f = fit_linear_response(x, y);
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(f.alpha[static_cast<std::size_t>(k)], alpha[static_cast<std::size_t>(k)], 1e-3);
    EXPECT_NEAR(f.sigma[static_cast<std::size_t>(k)], 0.005, 2.5e-4);
    EXPECT_GT(f.fit_r2[static_cast<std::size_t>(k)], 0.9);
  }
  // no excitation: α = 0, σ floored at 1e-4, R² = 0
  const LinearFit z = fit_linear_response({Pose6::Zero(), Pose6::Zero()}, {Pose6::Zero(), Pose6::Zero()});
  EXPECT_EQ(z.alpha[0], 0.0);
  EXPECT_EQ(z.sigma[0], 1e-4);
  EXPECT_EQ(z.fit_r2[0], 0.0);
  EXPECT_THROW(fit_linear_response({}, {}), std::invalid_argument);
}

TEST(ResponseCalibration, JsonRoundTripHashAndErrors) {
  ResponseCalibration c;
  c.task = "pick_cube";
  c.slice = {18, 21};
  c.fit.alpha = {0.08, 0.08, 0.08, 0.09, 0.09, 0.09};
  c.fit.sigma = {0.002, 0.002, 0.002, 0.004, 0.004, 0.004};
  c.fit.fit_r2 = {0.99, 0.99, 0.99, 0.98, 0.98, 0.98};
  c.episodes = 8;
  c.steps = 64;
  c.seed = 20260720;
  const auto back = ResponseCalibration::from_json(c.to_json(), "x.json");
  EXPECT_EQ(back.to_json(), c.to_json());
  EXPECT_EQ(back.sha256(), c.sha256());
  auto j = nlohmann::json::parse(c.to_json());
  j["sigma"][2] = 0.0;
  EXPECT_THAT([&] { ResponseCalibration::from_json(j.dump(), "cal.json"); },
              ThrowsMessage<InputError>(HasSubstr("cal.json: alpha/sigma: response model: sigma[2] must be finite and positive")));
  j = nlohmann::json::parse(c.to_json());
  j.erase("alpha");
  EXPECT_THAT([&] { ResponseCalibration::from_json(j.dump(), "cal.json"); }, ThrowsMessage<InputError>(HasSubstr("cal.json: alpha: missing field")));
  EXPECT_THAT([&] { ResponseCalibration::from_json("{", "cal.json"); }, ThrowsMessage<InputError>(HasSubstr("not valid JSON")));
  // values no fit produces were accepted (a 1e-300 sigma makes the belief certain after one step)
  const auto edited = [&](const char* key, const nlohmann::json& v) {
    auto e = nlohmann::json::parse(c.to_json());
    e[key] = v;
    return e.dump();
  };
  EXPECT_THAT([&] { ResponseCalibration::from_json(edited("sigma", {1e-300, 0.002, 0.002, 0.004, 0.004, 0.004}), "cal.json"); },
              ThrowsMessage<InputError>(HasSubstr("cal.json: sigma: must be at least 1e-4")));
  EXPECT_THAT([&] { ResponseCalibration::from_json(edited("fit_r2", {5, 0.99, 0.99, 0.98, 0.98, 0.98}), "cal.json"); },
              ThrowsMessage<InputError>(HasSubstr("cal.json: fit_r2: must be at most 1")));
  EXPECT_THAT([&] { ResponseCalibration::from_json(edited("alpha", {1e308, 0.08, 0.08, 0.09, 0.09, 0.09}), "cal.json"); },
              ThrowsMessage<InputError>(HasSubstr("cal.json: alpha: must be at most 1e3")));
  EXPECT_THAT([&] { ResponseCalibration::from_json(edited("rotation_mode", "identity"), "cal.json"); },
              ThrowsMessage<InputError>(HasSubstr("cal.json: rotation_mode: must be 'live'")));
}

}  // namespace
}  // namespace actionshift::adapt
