// a user method in another process: JSON lines over policy::LineProcess, one process per worker
#include "actionshift/eval/external_method.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/policy/line_process.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

namespace actionshift::eval {

namespace {

using nlohmann::json;

constexpr std::string_view kPrefix = "external:";

json inputs_json(const adapt::PluginInputs& in) {
  json pool = nullptr, cal = nullptr, grammar = nullptr;
  if (in.pool) {
    pool = json::array();
    for (const auto& c : *in.pool) pool.push_back(c.to_json_value());
  }
  if (in.model)
    cal = {{"alpha", in.model->alpha}, {"sigma", in.model->sigma}, {"gripper_alpha", in.model->gripper_alpha},
           {"gripper_sigma", in.model->gripper_sigma}};
  if (in.grammar)
    grammar = {{"scales", in.grammar->scales}, {"lags", in.grammar->lags}, {"targets", in.grammar->targets},
               {"frames", in.grammar->frames}, {"permutations", in.grammar->permutations}, {"signs", in.grammar->signs},
               {"gripper_inversion", in.grammar->gripper_inversion}};
  return {{"pool", pool}, {"calibration", cal}, {"grammar", grammar}};
}

std::vector<double> row_major(const Mat3& R) {
  std::vector<double> v;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) v.push_back(R(i, j));
  return v;
}

// one process per worker thread, started (and greeted) by the worker's first episode
struct Processes {
  std::string command;
  policy::ExternalOptions options;
  std::mutex mutex;
  std::map<std::thread::id, std::shared_ptr<policy::LineProcess>> by_thread;

  std::shared_ptr<policy::LineProcess> for_this_thread(const adapt::PluginInputs& in) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      const auto it = by_thread.find(std::this_thread::get_id());
      if (it != by_thread.end()) return it->second;
    }
    auto p = std::make_shared<policy::LineProcess>(command, "external method");
    const json hello = {{"type", "hello"},
                        {"protocol", std::string(kExternalMethodProtocol)},
                        {"task", in.task},
                        {"rung", std::string(adapt::rung_name(in.rung))},
                        {"params", in.params},
                        {"inputs", inputs_json(in)}};
    p->send(hello.dump(), "hello", options.hello_timeout_s);
    const std::string reply = p->receive(options.hello_timeout_s, "hello");
    if (!policy::is_ready_reply(reply)) p->fail("hello", "expected {\"type\":\"ready\"}");
    std::lock_guard<std::mutex> lock(mutex);
    by_thread[std::this_thread::get_id()] = p;
    return p;
  }
};

class ExternalMethodAdapter final : public adapt::Adapter {
 public:
  ExternalMethodAdapter(std::shared_ptr<policy::LineProcess> p, double step_timeout_s)
      : p_(std::move(p)), timeout_(step_timeout_s) {}
  std::string name() const override { return std::string(kPrefix) + p_->command(); }
  void begin_episode(std::uint64_t seed) override {
    step_ = 0;
    p_->send(json{{"type", "begin_episode"}, {"seed", seed}}.dump(), "begin_episode", timeout_);
  }
  Action encode(const Action& canonical, const Mat3& R) override {
    const std::string what = "encode " + std::to_string(step_);
    p_->send(json{{"type", "encode"}, {"canonical", std::vector<double>(canonical.data(), canonical.data() + kActionDim)},
                  {"R", row_major(R)}}
                 .dump(),
             what.c_str(), timeout_);
    const std::string reply = p_->receive(timeout_, what.c_str());
    try {
      const auto [raw, probe] = parse_encode_reply(reply);
      last_ = {probe, -1.0};
      return raw;
    } catch (const std::invalid_argument& e) {
      p_->fail(what, std::string("bad reply (") + e.what() + ")");
    }
  }
  void observe_fingers(double finger_delta) override { finger_ = finger_delta; }
  void observe(const Action& raw, const Pose6& response, const Mat3& R) override {
    const std::string what = "observe " + std::to_string(step_++);
    p_->send(json{{"type", "observe"}, {"raw", std::vector<double>(raw.data(), raw.data() + kActionDim)},
                  {"response", std::vector<double>(response.data(), response.data() + kPoseDim)}, {"R", row_major(R)},
                  {"finger_delta", finger_ ? json(*finger_) : json(nullptr)}}
                 .dump(),
             what.c_str(), timeout_);
    finger_.reset();
  }
  adapt::StepInfo last_step() const override { return last_; }

 private:
  std::shared_ptr<policy::LineProcess> p_;
  double timeout_;
  int step_{0};
  std::optional<double> finger_;
  adapt::StepInfo last_;
};

}  // namespace

std::pair<Action, bool> parse_encode_reply(std::string_view reply) {
  const json j = parse_json_input(std::string(reply), "reply", "");  // bounded depth, finite numbers
  if (!j.is_object() || !j.contains("raw") || !j["raw"].is_array() || j["raw"].size() != static_cast<std::size_t>(kActionDim))
    throw std::invalid_argument("expected {\"raw\": [7 numbers], \"probe\": bool}");
  Action a;
  for (int i = 0; i < kActionDim; ++i) {
    const json& v = j["raw"][static_cast<std::size_t>(i)];
    if (!v.is_number() || !std::isfinite(v.get<double>())) throw std::invalid_argument("raw[" + std::to_string(i) + "] is not a finite number");
    a[i] = v.get<double>();
  }
  bool probe = false;
  if (j.contains("probe")) {
    if (!j["probe"].is_boolean()) throw std::invalid_argument("probe must be true or false");
    probe = j["probe"].get<bool>();
  }
  return {a, probe};
}

adapt::MethodRegistration register_external_method(const std::string& command, adapt::Rung rung,
                                                    const std::vector<std::string>& files, const std::string& version,
                                                    policy::ExternalOptions options) {
  if (command.empty()) throw InputError("--method", "external", "empty command after 'external:'");
  if (command.size() > 480) throw InputError("--method", "external", "command longer than 480 characters (put it in a script)");
  for (const char c : command)
    if (c == '{' || c == '}' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      throw InputError("--method", "external", "the command holds '{', '}' or a control character (method labels use "
                                               "braces; put the command in a script)");
  adapt::MethodPlugin p;
  p.name = std::string(kPrefix) + command;
  p.version = version;
  p.rung = rung;
  p.files = files;
  auto processes = std::make_shared<Processes>();
  processes->command = command;
  processes->options = options;
  p.factory = [processes](const adapt::PluginInputs& in) -> std::unique_ptr<adapt::Adapter> {
    return std::make_unique<ExternalMethodAdapter>(processes->for_this_thread(in), processes->options.step_timeout_s);
  };
  return adapt::register_method(std::move(p), "external");
}

adapt::MethodRegistration register_external_method_of(const JobSpec& job, policy::ExternalOptions options) {
  if (!job.method_plugin || job.method_plugin->kind != "external" || !job.method.starts_with(kPrefix)) return {};
  if (adapt::find_method_plugin(job.method)) return {};  // registered already (by the caller's flags)
  return register_external_method(job.method.substr(kPrefix.size()),
                                  adapt::parse_rung(job.method_plugin->rung, "job", "method.plugin.rung"),
                                  job.method_plugin->files, job.method_plugin->version, options);
}

}  // namespace actionshift::eval
