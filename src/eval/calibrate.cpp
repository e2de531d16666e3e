#include "actionshift/eval/calibrate.hpp"

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

adapt::ResponseCalibration calibrate(std::shared_ptr<const sim::EnvModel> model, const CalibrationOptions& o) {
  if (o.episodes < 1) throw std::invalid_argument("calibration needs at least one episode");
  if (o.steps < 2) throw std::invalid_argument("calibration needs at least two steps per episode");
  const adapt::TcpSlice slice = tcp_slice(model->layout());
  const int steps = std::min(o.steps, model->horizon());
  sim::Env env(model);
  std::vector<Pose6> commanded, observed;
  for (int e = 0; e < o.episodes; ++e) {
    Eigen::VectorXd prev = env.reset(derive_seed({o.seed, static_cast<std::uint64_t>(e)}));
    Rng rng(derive_seed({o.seed, static_cast<std::uint64_t>(e), 1}));
    for (int t = 0; t < steps; ++t) {
      Action a;
      for (int c = 0; c < kActionDim; ++c) a[c] = rng.uniform(-1.0, 1.0);
      const sim::StepResult& r = env.step(a);
      if (r.safety != sim::SafetyFlag::kNone) break;
      commanded.push_back(a.head<kPoseDim>());
      observed.push_back(adapt::tcp_response(prev, r.obs, slice));
      prev = r.obs;
      if (r.episode_over()) break;
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
  return c;
}

}  // namespace actionshift::eval
