// run, plan (with the real resolver) and calibrate.
#include "cmd_run.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/experiment.hpp"
#include "actionshift/sim/task.hpp"
#include "commands.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

namespace actionshift::cli {

int run_run(const RunCliOptions& o) {
  eval::EpisodeFnOptions options;
  options.external.step_timeout_s = o.run.step_timeout_s;
  const EpisodeFnFactory factory = [options](const eval::JobSpec& job) { return eval::make_episode_fn(job, options); };
  if (!o.run.plan_file.empty()) return run_plan_jobs(o.run, factory);
  try {
    eval::JobRequest q = o.request;
    q.method.params = o.method_params;
    const eval::JobSpec job = eval::resolve_job(q, eval::default_resolver());
    return run_one_job(job, o.run, factory);
  } catch (const std::exception& e) {
    std::cerr << "actionshift: error: " << e.what() << "\n";
    return kBadInput;
  }
}

int run_plan_cli(const PlanOptions& o) { return run_plan(o, eval::default_resolver()); }

int run_calibrate(const CalibrateOptions& o) {
  if (!o.out.empty()) check_output_file(o.out, "--out");  // before the minutes of work, not after
  const auto model = sim::EnvModel::make(sim::parse_task(o.task));
  eval::CalibrationOptions co;
  co.episodes = o.episodes;
  co.steps = o.steps;
  co.seed = o.seed;
  const adapt::ResponseCalibration c = eval::calibrate(model, co);
  if (!o.out.empty()) {
    const std::filesystem::path p(o.out);
    std::error_code ec;
    if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
    if (ec) throw InputError(o.out, "--out", "cannot create the parent directory: " + ec.message());
    const std::string tmp = o.out + ".tmp";
    bool written = false;
    {
      std::ofstream f(tmp, std::ios::binary);
      f << c.to_json() << "\n";
      f.flush();
      written = static_cast<bool>(f);
    }
    if (written) std::filesystem::rename(tmp, o.out, ec);
    if (!written || ec) {
      std::filesystem::remove(tmp, ec);  // never leave the temporary file behind
      throw InputError(o.out, "--out", written ? "cannot rename the temporary file into place" : "cannot write the file");
    }
  }
  if (o.json) {
    std::cout << c.to_json() << "\n";
    return kOk;
  }
  static const char* kChannels[6] = {"dx", "dy", "dz", "rx", "ry", "rz"};
  std::cout << "response calibration: " << c.task << " (" << c.episodes << " episodes x " << c.steps
            << " steps of uniform random actions, seed " << c.seed << ")\n"
            << "tcp_pose at observation offset " << c.slice.position_start << "\n\n"
            << "channel   alpha [per unit]   sigma      R^2\n";
  for (int k = 0; k < 6; ++k) {
    const auto i = static_cast<std::size_t>(k);
    std::cout << std::left << std::setw(10) << kChannels[k] << std::right << std::setw(12) << std::fixed
              << std::setprecision(5) << c.fit.alpha[i] << std::setw(16) << c.fit.sigma[i] << std::setw(9)
              << std::setprecision(3) << c.fit.fit_r2[i] << "\n";
  }
  std::cout << "\ncalibration_sha256 " << c.sha256() << (o.out.empty() ? "" : "  written to " + o.out) << "\n";
  return kOk;
}

}  // namespace actionshift::cli
