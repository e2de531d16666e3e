// The native part of the `actionshift` Python package (python/actionshift/__init__.py wraps it).
// This is the only translation unit that includes pybind11: contracts and the core, manifests and
// pools, the hidden-contract environment (single and vectorised), adapters, the self-test, and
// evaluate() running a Python callable as the backbone through the library's own job runner.
#include "actionshift/adapt/plugin.hpp"
#include "actionshift/adapt/pool_belief.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/manifest.hpp"
#include "actionshift/core/transforms.hpp"
#include "actionshift/core/validate.hpp"
#include "actionshift/data/builtin_manifests.hpp"
#include "actionshift/eval/statistics.hpp"
#include "actionshift/eval/calibrate.hpp"
#include "actionshift/eval/episode_fn.hpp"
#include "actionshift/eval/experiment_yaml.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/provenance.hpp"
#include "actionshift/eval/resolve.hpp"
#include "actionshift/eval/runner.hpp"
#include "actionshift/policy/external.hpp"
#include "actionshift/policy/policy.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/render/camera.hpp"
#include "actionshift/render/image.hpp"
#include "actionshift/render/renderer.hpp"
#include "actionshift/selftest/audit.hpp"
#include "actionshift/selftest/library.hpp"
#include "actionshift/selftest/selftest.hpp"
#include "actionshift/selftest/verdict.hpp"
#include "actionshift/sim/controller.hpp"
#include "actionshift/sim/env.hpp"
#include "actionshift/sim/hidden_contract_env.hpp"
#include "actionshift/sim/robot_source.hpp"
#include "actionshift/sim/scene.hpp"
#include "actionshift/sim/task.hpp"
#include "actionshift/sim/vec_env.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace py = pybind11;
using namespace actionshift;

namespace {

using DArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// ---------------------------------------------------------------- conversions

[[noreturn]] void value_error(const std::string& msg) { throw py::value_error(msg); }

// A keyword constructor's parameter for bind_call: its name, what it takes, a check that converts
// a value as pybind11 would (throws py::cast_error if it cannot) and its default.
struct CallParam {
  const char* name;
  const char* expected;
  void (*check)(py::handle);
  py::object default_value;
};

template <class T>
void castable(py::handle h) {
  (void)h.cast<T>();
}

// A Python int that a failed conversion could not hold, as text (cut): `h` itself when the
// parameter takes one number (pybind11's int and float casters fail on an int only when it is out of
// the C type's range), or an element of a list or tuple `h` beyond 64 bits
std::optional<std::string> int_out_of_range(py::handle h, bool scalar_number) {
  const auto is_int = [](py::handle x) { return PyLong_Check(x.ptr()) && !PyBool_Check(x.ptr()); };
  if (is_int(h)) return scalar_number ? std::optional<std::string>(printable_input(std::string(py::str(h)), 40)) : std::nullopt;
  if (PyList_Check(h.ptr()) || PyTuple_Check(h.ptr()))
    for (py::handle x : h) {
      if (!is_int(x)) continue;
      int overflow = 0;
      (void)PyLong_AsLongLongAndOverflow(x.ptr(), &overflow);
      if (overflow != 0) return printable_input(std::string(py::str(x)), 40);
    }
  return std::nullopt;
}

// The arguments of a keyword constructor's catch-all overload (`*args, **kwargs`), bound to its
// parameters in order, defaults filled in and every given value checked. pybind11 answers a call
// that matches no signature with a TypeError of several lines (every signature, then the
// arguments); registered after the typed overload, this binds the call itself and says in one line
// what is wrong: too many positional arguments, an unknown or repeated keyword, or the first value
// that does not convert. (pybind11 tries every overload without implicit conversions before any
// with them, so a call that needs one, such as integers for floats, also arrives here.)
std::vector<py::object> bind_call(const char* callee, const std::vector<CallParam>& params, const py::args& args,
                                  const py::kwargs& kwargs) {
  const std::string who = std::string(callee) + "(): ";
  std::string names;
  for (const CallParam& p : params) names += (names.empty() ? "" : ", ") + std::string(p.name);
  if (args.size() > params.size())
    throw py::type_error(who + "takes at most " + std::to_string(params.size()) + " arguments (" + names + "), got " +
                         std::to_string(args.size()) + " positional");
  std::vector<py::object> values(params.size());
  for (std::size_t i = 0; i < args.size(); ++i) values[i] = py::reinterpret_borrow<py::object>(args[i]);
  for (auto item : kwargs) {
    const std::string key = py::str(item.first);
    const auto it = std::find_if(params.begin(), params.end(), [&](const CallParam& p) { return key == p.name; });
    if (it == params.end())
      throw py::type_error(who + "unknown keyword argument '" + key.substr(0, 80) + "' (known: " + names + ")");
    const auto k = static_cast<std::size_t>(it - params.begin());
    if (k < args.size()) throw py::type_error(who + "'" + key + "' given twice (by position and by keyword)");
    values[k] = py::reinterpret_borrow<py::object>(item.second);
  }
  for (std::size_t k = 0; k < params.size(); ++k) {
    if (!values[k]) {
      values[k] = params[k].default_value;
      continue;
    }
    try {
      params[k].check(values[k]);
    } catch (const py::cast_error&) {
      // an int is the right type but may not fit: say so, not "expected an int (got int)"
      const std::string_view expected = params[k].expected;
      if (const auto big = int_out_of_range(values[k], expected.starts_with("an int") || expected.starts_with("a number")))
        throw InputError(std::string(callee) + "()", params[k].name, "out of range: " + *big + " is too large in magnitude (expected " +
                                                                             params[k].expected + ")");
      throw py::type_error(who + params[k].name + ": expected " + params[k].expected + " (got " +
                           Py_TYPE(values[k].ptr())->tp_name + ")");
    }
  }
  return values;
}

Contract make_contract(std::vector<long long> permutation, std::vector<long long> sign, std::vector<double> scale,
                       std::string target, std::string frame, long long lag, bool gripper_inverted) {
  ContractFields f{std::move(permutation), std::move(sign), std::move(scale), std::move(target), std::move(frame), lag,
                   gripper_inverted};
  std::string err;
  auto c = Contract::try_make(f, &err);
  if (!c) throw InputError("contract", "", err);
  return *c;
}

std::string shape_of(const DArray& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

// pybind11's ensure() returns a null array (its error cleared) when h cannot be converted
// `h` as a C-contiguous array of doubles, or a null array (the caller reports it) if numpy cannot
// make an array of it. Only real numbers (bool, integer, float dtypes) are converted: forcecast
// alone would also turn complex numbers (dropping the imaginary part) and strings ("1.5") into
// doubles. A numpy array is inspected as it is; anything else through numpy's own type inference.
DArray ensure_numbers(py::handle h, const std::string& what) {
  py::array raw = py::isinstance<py::array>(h) ? py::reinterpret_borrow<py::array>(h) : py::array::ensure(h);
  if (!raw) return DArray();
  const char kind = raw.dtype().kind();
  if (kind != 'b' && kind != 'i' && kind != 'u' && kind != 'f')
    value_error(what + ": must hold real numbers (got dtype " + py::str(raw.dtype()).cast<std::string>() + ")");
  return DArray::ensure(raw);
}

DArray as_array(py::handle h, const char* what) {
  DArray a = ensure_numbers(h, what);
  if (!a) {
    PyErr_Clear();
    value_error(std::string(what) + ": not convertible to an array of numbers");
  }
  return a;
}

// a 1-D array of exactly n numbers (a list, tuple or numpy array of any numeric dtype)
template <int N>
Eigen::Matrix<double, N, 1> to_vec(py::handle h, const char* what) {
  DArray a = ensure_numbers(h, what);
  if (!a) {
    PyErr_Clear();
    value_error(std::string(what) + ": must be " + std::to_string(N) + " numbers");
  }
  if (a.ndim() != 1 || a.shape(0) != N)
    value_error(std::string(what) + ": must be " + std::to_string(N) + " numbers (got shape " + shape_of(a) + ")");
  Eigen::Matrix<double, N, 1> v;
  std::copy(a.data(), a.data() + N, v.data());
  return v;
}

Mat3 to_rotation(py::handle h, const char* what) {
  if (h.is_none()) return Mat3::Identity();
  DArray a = ensure_numbers(h, what);
  if (!a) {
    PyErr_Clear();
    value_error(std::string(what) + ": must be a 3x3 rotation matrix");
  }
  if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
    value_error(std::string(what) + ": must be a 3x3 rotation matrix (got shape " + shape_of(a) + ")");
  Mat3 R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = a.at(i, j);
  std::string why;
  if (!is_rotation(R, &why)) value_error(std::string(what) + ": " + why);
  return R;
}

Pose6 to_target(py::handle h) { return h.is_none() ? Pose6::Zero() : to_vec<kPoseDim>(h, "tracked_target"); }

DArray vec_out(const double* p, py::ssize_t n) {
  DArray out(n);
  std::copy(p, p + n, out.mutable_data());
  return out;
}
template <typename V>
DArray vec_out(const V& v) {
  return vec_out(v.data(), static_cast<py::ssize_t>(v.size()));
}

DArray mat_out(const Mat3& R) {
  DArray out({3, 3});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.mutable_at(i, j) = R(i, j);
  return out;
}

py::object json_to_py(const std::string& text) { return py::module_::import("json").attr("loads")(text); }
// JSON text of a Python value (a dict of params, a contract, a job spec), with one-line errors for
// what JSON cannot hold: NaN and infinity (which json.dumps would write as bare NaN), objects that
// are not numbers, strings, lists or dicts, and nesting deeper than Python's recursion limit
std::string py_to_json(py::handle h, const char* what = "value") {
  try {
    return py::module_::import("json").attr("dumps")(h, py::arg("allow_nan") = false).cast<std::string>();
  } catch (py::error_already_set& e) {
    std::string why;
    if (e.matches(PyExc_ValueError)) why = "NaN and infinity are not allowed (JSON has no such numbers)";
    else if (e.matches(PyExc_TypeError)) why = "holds a value JSON cannot represent (" + std::string(py::str(e.value())) + ")";
    else if (e.matches(PyExc_RecursionError)) why = "nested too deeply";
    else throw;
    value_error(std::string(what) + ": " + why);
  }
}

Contract contract_from_text(const std::string& text) {
  try {
    return Contract::from_json(text);
  } catch (const std::invalid_argument& e) {
    std::string why = e.what();
    if (why.rfind("contract: ", 0) == 0) why.erase(0, 10);  // the parser's own prefix: name it once
    throw InputError("contract", "", why);
  }
}

// a Contract, its JSON text or a dict of its fields
Contract to_contract(py::handle h) {
  if (py::isinstance<Contract>(h)) return h.cast<Contract>();
  if (py::isinstance<py::str>(h)) return contract_from_text(h.cast<std::string>());
  if (py::isinstance<py::dict>(h)) return contract_from_text(py_to_json(h, "contract"));
  throw py::type_error("contract: expected an actionshift.Contract, its JSON text or a dict");
}

std::vector<Contract> to_contracts(py::handle h, const char* what) {
  if (py::isinstance<py::str>(h)) return data::resolve_manifest(h.cast<std::string>()).contracts();
  if (py::isinstance<py::dict>(h) || !py::isinstance<py::iterable>(h))
    throw py::type_error(std::string(what) + ": expected a pool name, a manifest path or a list of contracts (got " +
                         Py_TYPE(h.ptr())->tp_name + ")");
  std::vector<Contract> out;
  for (py::handle x : h) {
    // selftest_library() gives (name, contract) pairs: the contract is the second
    const bool named = py::isinstance<py::tuple>(x) && py::len(x) == 2 && py::isinstance<py::str>(x[py::int_(0)]);
    out.push_back(to_contract(named ? py::handle(x[py::int_(1)]) : x));
  }
  if (out.empty()) value_error(std::string(what) + ": must not be empty");
  return out;
}

// ---------------------------------------------------------------- fidelity profile

// The one place a profile name becomes simulator settings. This build's simulator has a single
// fidelity profile, "maniskill" (the default EnvConfig); every other name is rejected.
sim::EnvConfig env_config_for_profile(const std::string& profile) {
  try {
    return sim::profile_config(profile);
  } catch (const std::invalid_argument& e) {
    throw InputError("profile", "", e.what());
  }
}

// Env models are immutable and shareable; building one loads the robot, so they are cached, by task,
// profile, observation noise and robot (its content hash; "" for the embedded Panda).
std::shared_ptr<const sim::EnvModel> env_model(sim::TaskId task, const std::string& profile, double obs_noise = 0.0,
                                               const sim::RobotSource* robot = nullptr) {
  static std::mutex mutex;
  static std::map<std::tuple<int, std::string, double, std::string>, std::shared_ptr<const sim::EnvModel>> cache;
  sim::EnvConfig config = env_config_for_profile(profile);
  config.obs_noise = obs_noise;
  std::lock_guard<std::mutex> lock(mutex);
  auto& m = cache[{static_cast<int>(task), profile, obs_noise, robot ? robot->sha256 : std::string()}];
  if (!m) m = sim::EnvModel::make(task, config, robot ? robot->description : nullptr);
  return m;
}

// What make()/make_vec() take besides the contract, as the CLI's --profile, --obs-noise, --robot and
// --package (docs/sim.md): checked here, so a bad value is a one-line InputError naming the argument.
struct EnvOptions {
  std::string task{"pick_cube"};
  std::string rotation{"live"}, profile{"maniskill"};
  std::optional<std::string> robot;   // URDF path (None: the embedded Panda)
  std::vector<std::string> packages;  // NAME=DIR, as --package
  double obs_noise{0.0};
  bool ignore_terminations{true};     // success does not end an episode (the runner's rule)
};

struct EnvModelRef {
  std::shared_ptr<const sim::EnvModel> model;
  std::string robot_sha256;  // "" for the embedded Panda
};

EnvModelRef resolve_env_model(const std::string& where, const EnvOptions& o) {
  const sim::TaskId task = sim::parse_task(o.task);
  if (!(o.obs_noise >= 0.0 && o.obs_noise <= sim::kMaxObsNoise)) {  // also rejects NaN
    std::ostringstream got;
    got << o.obs_noise;
    throw InputError(where, "obs_noise", "must be a finite sigma in [0, 0.1] (metres / radians; got " + got.str() + ")");
  }
  if (!o.robot) {
    if (!o.packages.empty()) throw InputError(where, "packages", "need robot= (a URDF file)");
    return {env_model(task, o.profile, o.obs_noise), ""};
  }
  const sim::RobotSource robot = sim::load_robot_source(*o.robot, sim::parse_package_args(o.packages));
  return {env_model(task, o.profile, o.obs_noise, &robot), robot.sha256};
}

// The episode-end rule of Env and VecEnv, the runner's (eval::make_episode_fn): an episode ends at
// the horizon or when a safety check fires; success ends it only with ignore_terminations=False.
struct StepFlags {
  bool terminated{false}, truncated{false};
  bool ended() const { return terminated || truncated; }
};
StepFlags step_flags(const sim::StepResult& r, bool ignore_terminations) {
  const bool safety = r.safety != sim::SafetyFlag::kNone;
  return {safety || (!ignore_terminations && r.success), r.truncated && !safety};
}

// the renderer of make(render_mode="rgb_array"): the CLI's (render::Renderer, the task's cameras)
struct RenderSetup {
  int width{320}, height{240};
  std::string camera{"default"};
};

render::Camera parse_env_camera(const std::string& where, const std::string& spec, sim::TaskId task) {
  try {
    return render::parse_camera(spec, task);
  } catch (const InputError& e) {
    throw InputError(where, "camera", e.reason());
  }
}

py::array_t<std::uint8_t> image_out(const render::Image& im) {
  py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(im.height()), static_cast<py::ssize_t>(im.width()), py::ssize_t{3}});
  std::copy(im.pixels().begin(), im.pixels().end(), out.mutable_data());
  return out;
}

sim::FrameRotation parse_rotation(const std::string& r) { return parse_rotation_mode(r, "rotation", ""); }

Manifest split_manifest(const std::string& name) {
  Manifest m = data::resolve_manifest(name);
  if (m.is_pool()) throw InputError(name, "kind", "is a pool, not a split manifest");
  return m;
}

// the contract of make()/make_vec(): explicit, or test[index] of a split, or identity
Contract pick_contract(py::handle contract, const std::optional<std::string>& split, std::int64_t index) {
  if (!split && index != 0) throw InputError("make", "index", "selects a split's contract: give split= too");
  if (!contract.is_none()) {
    if (split) throw InputError("make", "contract", "give either a contract or a split, not both");
    return to_contract(contract);
  }
  if (!split) return Contract::identity();
  const Manifest m = split_manifest(*split);
  const auto n = static_cast<std::int64_t>(m.test().size());
  if (index < 0 || index >= n)
    throw InputError(*split, "index", "out of range (the split has " + std::to_string(n) + " contracts, got " + std::to_string(index) + ")");
  return m.test()[static_cast<std::size_t>(index)].contract;
}

// ---------------------------------------------------------------- environments

py::dict step_info(const sim::StepResult& r, const sim::EpisodeStats& st) {
  py::dict info;
  info["success"] = r.success;
  info["success_once"] = st.success_once;
  info["success_at_end"] = st.success_at_end;
  info["safety"] = std::string(sim::safety_flag_name(r.safety));
  info["elapsed_steps"] = r.elapsed_steps;
  info["episode_return"] = st.episode_return;
  info["clipped_steps"] = st.clipped_steps;
  return info;
}

// a seed from Python: an integer in [0, 2**64), else a one-line ValueError (pybind11's own message
// for a failed conversion spans several lines)
std::uint64_t to_seed(py::handle h, const char* what) {
  const auto fail = [&] {
    PyErr_Clear();
    std::string got = py::repr(h);
    if (got.size() > 40 || got.find('\n') != std::string::npos) got = std::string("a ") + Py_TYPE(h.ptr())->tp_name;
    value_error(std::string(what) + ": must be an integer in [0, 2**64) (got " + got + ")");
  };
  if (py::isinstance<py::bool_>(h)) fail();
  const py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(h.ptr()));  // int, numpy integer
  if (!index) fail();
  const unsigned long long v = PyLong_AsUnsignedLongLong(index.ptr());
  if (PyErr_Occurred()) fail();
  return static_cast<std::uint64_t>(v);
}

// an integer argument from Python in [lo, hi], else a one-line ValueError
std::int64_t to_int(py::handle h, const char* what, std::int64_t lo, std::int64_t hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  const auto fail = [&] {
    PyErr_Clear();
    std::string got = py::repr(h);
    if (got.size() > 40 || got.find('\n') != std::string::npos) got = std::string("a ") + Py_TYPE(h.ptr())->tp_name;
    value_error(std::string(what) + ": must be an integer in " + range + " (got " + got + ")");
  };
  if (py::isinstance<py::bool_>(h)) fail();
  const py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(h.ptr()));
  if (!index) fail();
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (overflow != 0 || PyErr_Occurred() || v < lo || v > hi) fail();
  return v;
}

std::uint64_t next_seed(std::optional<std::uint64_t>& last) {
  last = last ? eval::splitmix64(*last) : 0;
  return *last;
}

// Closed environments: every later call raises this (close() itself may be called again).
// A member guarded by an environment's mutex, read or written from Python: the GIL is released before
// the mutex is taken (the lock order of PyEnv and PyVecEnv).
template <class T>
T read_guarded(std::mutex& m, const T& value) {
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(m);
  return value;
}
template <class T>
void write_guarded(std::mutex& m, T& value, T v) {
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> lock(m);
  value = std::move(v);
}

[[noreturn]] void closed_error() { throw std::runtime_error("environment is closed (close() released its simulation)"); }

// One environment under a hidden contract (identity if none was given). Observations come back as
// fresh numpy arrays (one copy of ~40 doubles, so a stored observation is never overwritten);
// actions are read in place when they are float64 and contiguous.
//
// Threads: the GIL is released while Bullet steps, so two Python threads could otherwise be inside
// one world at once (SIGSEGV in Bullet's island manager). Every call that touches the world holds
// mutex_, taken after the GIL is released (never the other way round, which would deadlock against a
// thread that holds the mutex and waits for the GIL) and released before the GIL is taken back: the
// results are copied out under the mutex, Python objects are built after. Concurrent calls take turns.
class PyEnv {
 public:
  PyEnv(const EnvOptions& o, py::handle contract, std::optional<std::string> split, std::int64_t index,
        std::optional<RenderSetup> render)
      : options_(o),
        ref_(resolve_env_model("make", o)),
        env_(std::make_unique<sim::HiddenContractEnv>(ref_.model, pick_contract(contract, split, index), parse_rotation(o.rotation))) {
    if (render) {
      render_ = *render;
      camera_ = parse_env_camera("make", render->camera, ref_.model->task());
    }
  }

  py::tuple reset(std::optional<std::uint64_t> seed) {
    Eigen::VectorXd obs;
    sim::StepResult last;
    sim::EpisodeStats episode;
    std::uint64_t s = 0;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      if (!env_) closed_error();
      s = seed ? *(last_seed_ = *seed) : next_seed(last_seed_);
      obs = env_->reset(s);
      started_ = true;
      last = env_->last();
      episode = env_->episode();
      ended_.reset();
    }
    py::dict info = step_info(last, episode);
    info["seed"] = s;
    return py::make_tuple(vec_out(obs), info);
  }

  py::tuple step(py::handle action) {
    DArray a = ensure_numbers(action, "action");
    if (!a) {
      PyErr_Clear();
      value_error("action: not convertible to an array of numbers");
    }
    // every wrong shape is the caller's error, raised before anything is simulated (the library's
    // environment would end the episode with bad_action_shape, as the runner records it)
    if (a.ndim() != 1 || a.shape(0) != kActionDim)
      value_error("action: must have shape (7,) (got " + shape_of(a) + ")");
    const std::span<const double> raw(a.data(), static_cast<std::size_t>(a.shape(0)));
    sim::StepResult r;
    sim::EpisodeStats episode;
    StepFlags flags;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      if (!env_) closed_error();
      if (!started_) throw std::runtime_error("step: called before reset() (call env.reset(seed=...) first)");
      if (ended_) {  // an ended episode returns its last result again (as the library's environment does)
        r = env_->last();
        flags = *ended_;
      } else {
        r = env_->step(raw);
        flags = step_flags(r, options_.ignore_terminations);
        if (flags.ended()) ended_ = flags;
      }
      episode = env_->episode();
    }
    return py::make_tuple(vec_out(r.obs), r.reward, flags.terminated, flags.truncated, step_info(r, episode));
  }

  // the current state drawn by OSMesa from the camera given to make(): (height, width, 3) uint8
  py::object render() {
    if (!render_) return py::none();
    render::Image im;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      if (!env_) closed_error();
      if (!started_) throw std::runtime_error("render: called before reset() (the scene has no objects until then)");
      if (!renderer_) renderer_ = std::make_unique<render::Renderer>(render_->width, render_->height);
      im = renderer_->render(env_->scene(), camera_);
    }
    return image_out(im);
  }

  // frees the Bullet world; waits for a call of another thread to finish first
  void close() {
    std::unique_ptr<sim::HiddenContractEnv> gone;
    std::unique_ptr<render::Renderer> renderer;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      gone = std::move(env_);
      gone.reset();
      renderer = std::move(renderer_);
      renderer.reset();
    }
  }

  // fixed at construction: read from the shared model, never from the world
  std::string task() const { return std::string(sim::task_name(ref_.model->task())); }
  int horizon() const { return ref_.model->horizon(); }
  int obs_dim() const { return ref_.model->layout().size(); }
  py::list layout() const {
    py::list out;
    for (const auto& f : ref_.model->layout().fields()) {
      py::dict d;
      d["name"] = f.name;
      d["offset"] = f.offset;
      d["width"] = f.width;
      out.append(d);
    }
    return out;
  }
  const std::string& profile() const { return options_.profile; }
  const std::string& rotation() const { return options_.rotation; }
  const std::string& robot_sha256() const { return ref_.robot_sha256; }
  // the seed of the last reset (None before the first): what a pickled environment carries
  std::optional<std::uint64_t> last_seed() { return read_guarded(mutex_, last_seed_); }
  void set_last_seed(std::optional<std::uint64_t> s) { write_guarded(mutex_, last_seed_, s); }

 private:
  EnvOptions options_;
  EnvModelRef ref_;
  std::mutex mutex_;                               // guards everything below
  std::unique_ptr<sim::HiddenContractEnv> env_;    // null once closed
  std::optional<std::uint64_t> last_seed_;
  bool started_{false};                            // reset() was called
  std::optional<StepFlags> ended_;                 // set once the episode has ended
  std::optional<RenderSetup> render_;
  render::Camera camera_;
  std::unique_ptr<render::Renderer> renderer_;     // made at the first render()
};

// num_envs environments stepped together on worker threads (the GIL is released while they step).
// Environment i runs the given contract, or test[(index + i) mod n] of a split; reset(seed) seeds
// environment i with seed + i. An environment whose episode ends (terminated or truncated) is
// reset in the same call: the returned row is the new episode's first observation and
// info["final_obs"][i] the last one of the ended episode. Calls from several Python threads take turns
// on mutex_ (taken with the GIL released, as in PyEnv); close() frees the worlds and the worker threads.
// each environment holds its own Bullet world, about 0.2 MB once reset: 4096 of them take about 1 GB
constexpr int kMaxNumEnvs = 4096;

class PyVecEnv {
 public:
  PyVecEnv(const EnvOptions& o, int num_envs, py::handle contract, std::optional<std::string> split, std::int64_t index,
           unsigned threads)
      : options_(o) {
    if (num_envs < 1 || num_envs > kMaxNumEnvs)
      throw InputError("make_vec", "num_envs", "must be between 1 and " + std::to_string(kMaxNumEnvs) + " (got " +
                                                   std::to_string(num_envs) + ")");
    ref_ = resolve_env_model("make_vec", o);
    const sim::FrameRotation rot = parse_rotation(o.rotation);
    std::vector<Contract> contracts;
    if (split && contract.is_none()) {
      const Manifest m = split_manifest(*split);
      const auto n = static_cast<std::int64_t>(m.test().size());
      if (index < 0 || index >= n)
        throw InputError(*split, "index", "out of range (the split has " + std::to_string(n) + " contracts, got " + std::to_string(index) + ")");
      for (int i = 0; i < num_envs; ++i) contracts.push_back(m.test()[static_cast<std::size_t>((index + i) % n)].contract);
    } else {
      contracts.assign(static_cast<std::size_t>(num_envs), pick_contract(contract, split, index));
    }
    seeds_.assign(static_cast<std::size_t>(num_envs), 0);
    vec_ = std::make_unique<sim::VecEnv>(ref_.model, contracts, rot, threads);  // 0: all cores; at most one per environment
    num_envs_ = num_envs;
    threads_ = vec_->threads();
  }

  // fixed at construction (readable after close)
  int num_envs() const { return num_envs_; }
  int obs_dim() const { return ref_.model->layout().size(); }
  int horizon() const { return ref_.model->horizon(); }
  unsigned threads() const { return threads_; }
  const std::string& robot_sha256() const { return ref_.robot_sha256; }

  py::tuple reset(std::optional<std::uint64_t> seed) {
    const auto n = static_cast<std::size_t>(num_envs_);
    DArray obs({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(obs_dim())});
    double* out = obs.mutable_data();
    std::vector<std::uint64_t> seeds;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      if (!vec_) closed_error();
      const std::uint64_t base = seed ? *(last_seed_ = *seed) : next_seed(last_seed_);
      vec_->for_each([&](int e) {
        const auto i = static_cast<std::size_t>(e);
        seeds_[i] = base + i;
        const Eigen::VectorXd& o = vec_->env(e).reset(seeds_[i]);
        std::copy(o.data(), o.data() + o.size(), out + i * static_cast<std::size_t>(o.size()));
      });
      started_ = true;
      seeds = seeds_;
    }
    py::dict info = infos(std::vector<Row>(n));
    info["seed"] = vec_u64(seeds);
    return py::make_tuple(obs, info);
  }

  // frees every world and the worker threads; waits for a call of another thread to finish first
  void close() {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mutex_);
    vec_.reset();
  }

  py::tuple step(py::handle actions) {
    DArray a = ensure_numbers(actions, "actions");
    if (!a) {
      PyErr_Clear();
      value_error("actions: not convertible to an array of numbers");
    }
    const auto n = static_cast<std::size_t>(num_envs_);
    if (a.ndim() != 2 || a.shape(0) != static_cast<py::ssize_t>(n) || a.shape(1) != kActionDim)
      value_error("actions: must have shape (" + std::to_string(n) + ", 7) (got " + shape_of(a) + ")");
    const auto d = static_cast<std::size_t>(obs_dim());
    DArray obs({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d)});
    DArray final_obs({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d)});
    std::vector<Row> rows(n);
    const double* in = a.data();
    double* o = obs.mutable_data();
    double* fo = final_obs.mutable_data();
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      if (!vec_) closed_error();
      if (!started_) throw std::runtime_error("step: called before reset() (call envs.reset(seed=...) first)");
      vec_->step(std::span<const double>(in, n * kActionDim), [&](int e, const sim::StepResult& r) {
        const auto i = static_cast<std::size_t>(e);
        Row& row = rows[i];
        row.result_of(r, vec_->env(e).episode(), step_flags(r, options_.ignore_terminations));
        std::copy(r.obs.data(), r.obs.data() + d, fo + i * d);
        if (row.flags.ended()) {
          seeds_[i] = eval::splitmix64(seeds_[i]);
          const Eigen::VectorXd& first = vec_->env(e).reset(seeds_[i]);
          std::copy(first.data(), first.data() + d, o + i * d);
        } else {
          std::copy(r.obs.data(), r.obs.data() + d, o + i * d);
        }
      });
    }
    py::array_t<double> reward(static_cast<py::ssize_t>(n));
    py::array_t<bool> term(static_cast<py::ssize_t>(n)), trunc(static_cast<py::ssize_t>(n)), ended(static_cast<py::ssize_t>(n));
    for (std::size_t i = 0; i < n; ++i) {
      reward.mutable_data()[i] = rows[i].reward;
      term.mutable_data()[i] = rows[i].flags.terminated;
      trunc.mutable_data()[i] = rows[i].flags.truncated;
      ended.mutable_data()[i] = rows[i].flags.ended();
    }
    // the info of the step just taken (an ended environment's row: its episode's last step), and,
    // as Gymnasium's same-step autoreset puts them, the ended episodes' last observation and info
    py::dict info = infos(rows);
    info["final_obs"] = final_obs;
    info["_final_obs"] = ended;
    info["final_info"] = infos(rows);
    info["_final_info"] = ended;
    info["autoreset"] = ended;
    return py::make_tuple(obs, reward, term, trunc, info);
  }

  // the base seed of the last reset (None before the first): what a pickled environment carries
  std::optional<std::uint64_t> last_seed() { return read_guarded(mutex_, last_seed_); }
  void set_last_seed(std::optional<std::uint64_t> s) { write_guarded(mutex_, last_seed_, s); }

 private:
  // one environment's step, copied out on its worker thread
  struct Row {
    double reward{0.0};
    StepFlags flags;
    bool success{false}, success_once{false}, success_at_end{false};
    sim::SafetyFlag safety{sim::SafetyFlag::kNone};
    int elapsed_steps{0}, clipped_steps{0};
    double episode_return{0.0};
    void result_of(const sim::StepResult& r, const sim::EpisodeStats& st, StepFlags f) {
      reward = r.reward;
      flags = f;
      success = r.success;
      success_once = st.success_once;
      success_at_end = st.success_at_end;
      safety = r.safety;
      elapsed_steps = r.elapsed_steps;
      clipped_steps = st.clipped_steps;
      episode_return = st.episode_return;
    }
  };
  // Env's info keys, one array each (Gymnasium's vector infos)
  static py::dict infos(const std::vector<Row>& rows) {
    const auto n = static_cast<py::ssize_t>(rows.size());
    py::array_t<bool> success(n), success_once(n), success_at_end(n);
    py::array_t<std::int64_t> elapsed(n), clipped(n);
    py::array_t<double> ret(n);
    py::list safety;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      success.mutable_data()[i] = rows[i].success;
      success_once.mutable_data()[i] = rows[i].success_once;
      success_at_end.mutable_data()[i] = rows[i].success_at_end;
      elapsed.mutable_data()[i] = rows[i].elapsed_steps;
      clipped.mutable_data()[i] = rows[i].clipped_steps;
      ret.mutable_data()[i] = rows[i].episode_return;
      safety.append(std::string(sim::safety_flag_name(rows[i].safety)));
    }
    py::dict info;
    info["success"] = success;
    info["success_once"] = success_once;
    info["success_at_end"] = success_at_end;
    info["safety"] = py::module_::import("numpy").attr("array")(safety);
    info["elapsed_steps"] = elapsed;
    info["episode_return"] = ret;
    info["clipped_steps"] = clipped;
    return info;
  }
  static py::array_t<std::uint64_t> vec_u64(const std::vector<std::uint64_t>& v) {
    py::array_t<std::uint64_t> out(static_cast<py::ssize_t>(v.size()));
    std::copy(v.begin(), v.end(), out.mutable_data());
    return out;
  }
  EnvOptions options_;
  EnvModelRef ref_;
  int num_envs_{0};
  unsigned threads_{1};
  std::mutex mutex_;                          // guards everything below
  std::unique_ptr<sim::VecEnv> vec_;         // the environments and their worker pool; null once closed
  std::vector<std::uint64_t> seeds_;
  std::optional<std::uint64_t> last_seed_;
  bool started_{false};
};

// Frames as `actionshift render` writes them: FILE.gif (every frame, then the last held for a
// second) or FILE.png (frame `frame`, -1: the last). Frames are (height, width, 3) uint8 arrays.
void write_frames(const std::string& path, py::handle frames, int delay_cs, int frame) {
  namespace fs = std::filesystem;
  const std::string ext = fs::path(path).extension().string();
  if (ext != ".gif" && ext != ".png") throw InputError(path, "path", "must end in .gif or .png");
  if (fs::is_directory(path)) throw InputError(path, "path", "is a directory");
  if (delay_cs < 1 || delay_cs > 1000) throw InputError("write_frames", "delay_cs", "must be in 1..1000");
  if (!py::isinstance<py::sequence>(frames) || py::isinstance<py::str>(frames))
    throw py::type_error("write_frames: frames: expected a sequence of (height, width, 3) uint8 arrays");
  std::vector<render::Image> images;
  const py::sequence seq = py::reinterpret_borrow<py::sequence>(frames);
  for (std::size_t k = 0; k < seq.size(); ++k) {
    const py::object f = seq[k];
    const std::string what = "frames[" + std::to_string(k) + "]";
    if (!py::isinstance<py::array>(f) || !py::array(py::reinterpret_borrow<py::array>(f)).dtype().is(py::dtype::of<std::uint8_t>()))
      throw InputError("write_frames", what, "must be a numpy uint8 array (what env.render() returns)");
    const auto a = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(f);
    if (a.ndim() != 3 || a.shape(2) != 3 || a.shape(0) < 1 || a.shape(1) < 1 || a.shape(0) > 8192 || a.shape(1) > 8192)
      throw InputError("write_frames", what, "must have shape (height, width, 3) with sides in 1..8192");
    render::Image im(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
    std::copy(a.data(), a.data() + a.size(), im.mutable_pixels().begin());
    if (!images.empty() && (im.width() != images.front().width() || im.height() != images.front().height()))
      throw InputError("write_frames", what, "has another size than frames[0]");
    images.push_back(std::move(im));
  }
  if (images.empty()) throw InputError("write_frames", "frames", "no frame to write");
  py::gil_scoped_release release;
  if (ext == ".png") {
    if (frame < -1 || frame >= static_cast<int>(images.size()))
      throw InputError("write_frames", "frame", std::to_string(frame) + " is outside 0.." + std::to_string(images.size() - 1) + " (-1: the last)");
    render::write_png(path, frame < 0 ? images.back() : images[static_cast<std::size_t>(frame)]);
    return;
  }
  const render::Image last = images.back();
  for (int i = 0; i < 10; ++i) images.push_back(last);  // hold the outcome for a second, as the CLI does
  render::write_gif(path, images, delay_cs);
}

// make(calibration=...) and evaluate(calibration=...): a response calibration (a dict as `calibrate
// --json` writes it, or its file) measured for this task on this profile
adapt::ResponseCalibration resolve_calibration(py::handle calibration, const std::string& task, const std::string& profile) {
  const std::string t(sim::task_name(sim::parse_task(task)));
  adapt::ResponseCalibration cal;
  if (py::isinstance<py::dict>(calibration)) {
    cal = adapt::ResponseCalibration::from_json(py_to_json(calibration, "calibration"), "calibration");
    if (cal.task != t) throw InputError("calibration", "task", "is " + cal.task + ", not the environment's " + t);
    const std::string base = cal.profile.substr(0, cal.profile.find('['));
    if (base != profile) throw InputError("calibration", "profile", "was measured on " + cal.profile + ", not on the environment's " + profile);
  } else {
    const std::string path = py::str(py::module_::import("os").attr("fspath")(calibration)).cast<std::string>();
    cal = adapt::ResponseCalibration::load_for(path, t, "the environment's " + t, profile, "the environment's " + profile);
  }
  return cal;
}

// ... returned as its canonical dict (env.calibration)
py::object load_calibration(py::handle calibration, const std::string& task, const std::string& profile) {
  return json_to_py(resolve_calibration(calibration, task, profile).to_json());
}

// The C++ baseline of the per-step benchmark (tests/bench/python_bench.py): the same control loop
// as stepping an Env from Python (identity contract, reset with seed, seed+1, ... at each episode
// end), over the rows of `actions`, in C++. Returns the wall time [s] of the loop.
double bench_cpp_steps(const std::string& task, const DArray& actions, std::uint64_t seed, const std::string& profile) {
  if (actions.ndim() != 2 || actions.shape(1) != kActionDim) value_error("actions: must have shape (N, 7)");
  sim::HiddenContractEnv env(env_model(sim::parse_task(task), profile), Contract::identity());
  const double* a = actions.data();
  const auto n = static_cast<std::size_t>(actions.shape(0));
  py::gil_scoped_release release;
  const auto t0 = std::chrono::steady_clock::now();
  env.reset(seed);
  double sink = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const sim::StepResult& r = env.step(std::span<const double>(a + i * kActionDim, kActionDim));
    sink += r.obs[0];
    if (r.episode_over()) env.reset(++seed);
  }
  const auto t1 = std::chrono::steady_clock::now();
  if (!std::isfinite(sink)) return -1.0;
  return std::chrono::duration<double>(t1 - t0).count();
}

// ---------------------------------------------------------------- in-process backbone

// copy.deepcopy(obj); the GIL must be held
py::object deepcopy(const py::object& obj) { return py::module_::import("copy").attr("deepcopy")(obj); }

// pybind11's gil_scoped_acquire on a thread without a Python thread state creates one and deletes
// it again on release. Called from a runner worker, every policy call allocated a thread state and
// its frame stack (mmap) and freed them (munmap, whose TLB shootdown interrupts the other cores):
// a 2-thread evaluate() used 50 % more CPU than a 1-thread one. The first call on such a thread
// registers one thread state for the rest of the thread's life (PyGILState_Ensure keeps it while
// its count is above zero), which gil_scoped_acquire then finds and reuses; it is deleted when the
// thread exits (run_job joins its workers while the caller has released the GIL).
class KeptThreadState {
 public:
  KeptThreadState() : state_(PyGILState_Ensure()), saved_(PyEval_SaveThread()) {}
  ~KeptThreadState() {
    PyEval_RestoreThread(saved_);
    PyGILState_Release(state_);
  }
  KeptThreadState(const KeptThreadState&) = delete;
  KeptThreadState& operator=(const KeptThreadState&) = delete;

 private:
  PyGILState_STATE state_;
  PyThreadState* saved_;
};

// call before gil_scoped_acquire on a thread that may not be Python's (without the GIL)
void keep_python_thread_state() {
  if (PyGILState_GetThisThreadState() != nullptr) return;  // a Python thread, or kept already
  thread_local KeptThreadState kept;
}

// A Python callable obs -> 7 numbers as a policy::Policy. reset() calls the object's `reset()`
// method if it has one. Clones share the one Python object (one worker), or each is a deep copy.
class PythonPolicy final : public policy::Policy {
 public:
  // copy_per_worker: every clone() is a copy.deepcopy of the callable (one per runner worker, as the
  // external-process backbone starts one process per worker); otherwise clones share the callable
  PythonPolicy(py::object fn, std::string name, std::string sha256, sim::TaskId task, bool copy_per_worker = false)
      : fn_(std::make_shared<py::object>(std::move(fn))), name_(std::move(name)), sha_(std::move(sha256)), task_(task),
        copy_(copy_per_worker) {}
  ~PythonPolicy() override {
    py::gil_scoped_acquire gil;
    fn_.reset();
  }
  void reset() override {
    keep_python_thread_state();
    py::gil_scoped_acquire gil;
    if (py::hasattr(*fn_, "reset")) fn_->attr("reset")();
  }
  Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) override {
    policy::check_observation(obs, task_);
    keep_python_thread_state();
    py::gil_scoped_acquire gil;
    py::object out = (*fn_)(vec_out(obs.data(), obs.size()));
    Action a = to_vec<kActionDim>(out, "policy output");
    return a;
  }
  std::string name() const override { return name_; }
  std::string sha256() const override { return sha_; }
  sim::TaskId task() const override { return task_; }
  std::unique_ptr<policy::Policy> clone() const override {
    keep_python_thread_state();
    py::gil_scoped_acquire gil;
    if (!copy_) return std::make_unique<PythonPolicy>(*fn_, name_, sha_, task_);
    return std::make_unique<PythonPolicy>(deepcopy(*fn_), name_, sha_, task_);
  }

 private:
  std::shared_ptr<py::object> fn_;
  std::string name_, sha_;
  sim::TaskId task_;
  bool copy_{false};
};

// The policy-call part of the evaluation benchmark (tests/bench/python_bench.py): the same
// observation handed `calls` times to the Python callable `policy` exactly as evaluate() calls it
// (from a thread without the GIL, which act() takes), and to the external-process backbone running
// `command` (a JSON-lines round trip each). Returns the wall times [s] of the two loops
// {in_process_s, external_s}; the external process is started and greeted before its clock starts.
py::dict bench_policy_calls(py::object policy, const std::string& command, const std::string& task, std::int64_t calls) {
  if (!PyCallable_Check(policy.ptr())) throw py::type_error("policy: must be callable (obs -> 7 numbers)");
  if (calls <= 0) value_error("calls: must be positive");
  const sim::TaskId id = sim::parse_task(task);
  sim::HiddenContractEnv env(env_model(id, "maniskill"), Contract::identity());
  const Eigen::VectorXd obs = env.reset(1);
  PythonPolicy in_process(policy, "bench", sha256_hex("bench"), id);
  double in_s = 0.0, ext_s = 0.0, sink = 0.0;
  {
    py::gil_scoped_release release;
    policy::ExternalPolicy external(command, id);
    in_process.reset();
    external.reset();
    auto t0 = std::chrono::steady_clock::now();
    for (std::int64_t i = 0; i < calls; ++i) sink += in_process.act(obs)(0);
    auto t1 = std::chrono::steady_clock::now();
    in_s = std::chrono::duration<double>(t1 - t0).count();
    t0 = std::chrono::steady_clock::now();
    for (std::int64_t i = 0; i < calls; ++i) sink += external.act(obs)(0);
    t1 = std::chrono::steady_clock::now();
    ext_s = std::chrono::duration<double>(t1 - t0).count();
  }
  py::dict d;
  d["in_process_s"] = in_s;
  d["external_s"] = ext_s;
  d["checksum"] = sink;
  return d;
}

// ---------------------------------------------------------------- user methods from Python

// What a Python method is handed before each episode (setup(inputs)): exactly its rung's inputs.
py::dict plugin_inputs_dict(const adapt::PluginInputs& in) {
  py::dict d;
  d["task"] = in.task;
  d["rung"] = std::string(adapt::rung_name(in.rung));
  d["params"] = json_to_py(in.params.dump());
  d["pool"] = in.pool ? py::cast(*in.pool) : py::none();
  d["calibration"] = in.model ? py::cast(*in.model) : py::none();
  if (in.grammar) {
    py::dict g;
    g["scales"] = in.grammar->scales;
    g["lags"] = in.grammar->lags;
    g["targets"] = in.grammar->targets;
    g["frames"] = in.grammar->frames;
    g["permutations"] = in.grammar->permutations;
    g["signs"] = in.grammar->signs;
    g["gripper_inversion"] = in.grammar->gripper_inversion;
    d["grammar"] = g;
  } else {
    d["grammar"] = py::none();
  }
  return d;
}

// A Python object with begin_episode / encode / observe (and optionally setup, observe_fingers) as an
// adapt::Adapter. encode returns 7 numbers, or (7 numbers, probe) to mark a probe step.
class PythonAdapter final : public adapt::Adapter {
 public:
  PythonAdapter(std::shared_ptr<py::object> obj, std::string name, const adapt::PluginInputs& in)
      : obj_(std::move(obj)), name_(std::move(name)) {
    py::gil_scoped_acquire gil;
    if (py::hasattr(*obj_, "setup")) obj_->attr("setup")(plugin_inputs_dict(in));
  }
  ~PythonAdapter() override {
    py::gil_scoped_acquire gil;
    obj_.reset();
  }
  std::string name() const override { return name_; }
  void begin_episode(std::uint64_t seed) override {
    keep_python_thread_state();
    py::gil_scoped_acquire gil;
    if (py::hasattr(*obj_, "begin_episode")) obj_->attr("begin_episode")(seed);
  }
  Action encode(const Action& canonical, const Mat3& R) override {
    keep_python_thread_state();
    py::gil_scoped_acquire gil;
    py::object out = obj_->attr("encode")(vec_out(canonical), mat_out(R));
    last_ = {};
    if (py::isinstance<py::tuple>(out) && py::len(out) == 2) {
      last_.probe = py::bool_(out[py::int_(1)]);
      out = out[py::int_(0)];
    }
    const std::string what = "method " + name_ + ": encode";
    Action raw;
    try {
      raw = to_vec<kActionDim>(out, what.c_str());
    } catch (py::error_already_set& e) {
      throw InputError("method " + name_, "encode", std::string(py::str(e.value())));
    }
    if (!raw.allFinite()) throw InputError("method " + name_, "encode", "returned a NaN or infinite raw action");
    return raw;
  }
  void observe(const Action& raw, const Pose6& response, const Mat3& R) override {
    keep_python_thread_state();
    py::gil_scoped_acquire gil;
    if (py::hasattr(*obj_, "observe")) obj_->attr("observe")(vec_out(raw), vec_out(response), mat_out(R));
  }
  void observe_fingers(double finger_delta) override {
    keep_python_thread_state();
    py::gil_scoped_acquire gil;
    if (py::hasattr(*obj_, "observe_fingers")) obj_->attr("observe_fingers")(finger_delta);
  }
  adapt::StepInfo last_step() const override { return last_; }

 private:
  std::shared_ptr<py::object> obj_;
  std::string name_;
  adapt::StepInfo last_;
};

// The Python method's objects: the one given (one worker) or a copy.deepcopy per worker thread.
struct PythonMethodObjects {
  std::shared_ptr<py::object> prototype;
  bool copy_per_worker{false};
  std::mutex mutex;
  std::map<std::thread::id, std::shared_ptr<py::object>> copies;

  std::shared_ptr<py::object> for_this_thread() {
    if (!copy_per_worker) return prototype;
    std::lock_guard<std::mutex> lock(mutex);
    auto& c = copies[std::this_thread::get_id()];
    if (!c) {
      keep_python_thread_state();
      py::gil_scoped_acquire gil;
      c = std::make_shared<py::object>(deepcopy(*prototype));
    }
    return c;
  }
  ~PythonMethodObjects() {
    py::gil_scoped_acquire gil;
    copies.clear();
    prototype.reset();
  }
};

// Registers a Python method object for the duration of one evaluate() call.
adapt::MethodRegistration register_python_method(py::object obj, const py::dict& identity, unsigned workers) {
  adapt::MethodPlugin p;
  p.name = identity["name"].cast<std::string>();
  p.version = identity["version"].cast<std::string>();
  p.rung = adapt::parse_rung(identity["rung"].cast<std::string>(), "method " + p.name, "rung");
  p.code_sha256 = identity["code_sha256"].cast<std::string>();
  p.files = identity["files"].cast<std::vector<std::string>>();
  p.params = parse_json_input(identity["params"].cast<std::string>(), "method " + p.name, "params");
  for (const char* m : {"begin_episode", "encode"})
    if (!py::hasattr(obj, m))
      throw InputError("method " + p.name, m, "missing: a method object has begin_episode(seed), encode(canonical, R) and observe(raw, response, R)");
  auto objects = std::make_shared<PythonMethodObjects>();
  objects->prototype = std::make_shared<py::object>(std::move(obj));
  objects->copy_per_worker = workers > 1;
  if (objects->copy_per_worker) {
    try {
      deepcopy(*objects->prototype);
    } catch (py::error_already_set& e) {
      const std::string why = e.what();
      throw InputError("evaluate", "threads",
                       "each of the " + std::to_string(workers) + " workers needs copy.deepcopy(method), which failed (" +
                           why.substr(0, why.find('\n')) + "); use threads=1");
    }
  }
  const std::string name = p.name;
  p.factory = [objects, name](const adapt::PluginInputs& in) -> std::unique_ptr<adapt::Adapter> {
    return std::make_unique<PythonAdapter>(objects->for_this_thread(), name, in);
  };
  return adapt::register_method(std::move(p), "python");
}

// backbone identity of a Python policy: "external:<command>" hashes the command exactly as the
// external-process backbone does (so the job is the one `actionshift run --backbone` writes);
// any other name is hashed as a whole.
eval::BackboneRef backbone_ref(const std::string& name, sim::TaskId task) {
  if (name.empty()) throw InputError("evaluate", "backbone", "must not be empty");
  if (name.starts_with("external:")) {
    try {
      const policy::BackboneIdentity b = policy::backbone_identity(name, task);  // the CLI's identity
      return {b.name, b.sha256};
    } catch (const InputError& e) {
      throw InputError("evaluate", e.field(), e.reason());
    }
  }
  return {name, sha256_hex(name)};
}

py::dict evaluate(py::object policy, const std::string& task, const std::string& split, const std::string& method,
                  std::uint64_t seed, std::int64_t episodes, const std::string& out, const std::string& backbone,
                  std::optional<std::string> pool, py::object params, const std::string& rotation,
                  const std::string& profile, const std::string& progress, int threads, py::object method_object,
                  py::object method_identity, std::optional<std::string> backbone_sha256, std::optional<std::string> robot,
                  const std::vector<std::string>& packages, double obs_noise, py::object calibration, int horizon) {
  // a string names a backbone of the library (expert, mlp:..., ppo:..., external:...), as `run --backbone`
  const bool builtin_backbone = py::isinstance<py::str>(policy);
  if (!builtin_backbone && !PyCallable_Check(policy.ptr()))
    throw py::type_error("policy: must be callable (obs -> 7 numbers) or a backbone name");
  if (threads < 0) throw InputError("evaluate", "threads", "must be 0 (all cores) or a positive count (got " + std::to_string(threads) + ")");
  env_config_for_profile(profile);  // validates the name
  eval::JobRequest q;
  q.profile = profile;
  q.task = task;
  q.split = split;
  q.method.name = method;
  q.method.params = params.is_none() ? "{}" : (py::isinstance<py::str>(params) ? params.cast<std::string>() : py_to_json(params, "params"));
  q.backbone = backbone;
  q.pool = pool;
  q.rotation_mode = rotation;
  q.seed = seed;
  q.episodes = episodes;
  q.obs_noise = obs_noise;
  q.horizon = horizon;  // checked with the job (validate_job): 0 is the task's
  q.source = "evaluate";
  if (!(obs_noise >= 0.0 && obs_noise <= sim::kMaxObsNoise)) {  // also rejects NaN
    std::ostringstream got;
    got << obs_noise;
    throw InputError("evaluate", "obs_noise", "must be a finite sigma in [0, 0.1] (metres / radians; got " + got.str() + ")");
  }
  if (!robot && !packages.empty()) throw InputError("evaluate", "packages", "need robot= (a URDF file)");
  eval::PlanResolver resolver = eval::default_resolver();
  if (builtin_backbone) resolver.backbone = eval::default_resolver().backbone;  // the CLI's identity
  else resolver.backbone = [&backbone_sha256](const std::string& t, const std::string& name) {
    eval::BackboneRef ref = backbone_ref(name, sim::parse_task(t));
    if (backbone_sha256 && !name.starts_with("external:")) ref.sha256 = *backbone_sha256;  // the callable's content
    return ref;
  };
  // threads > 1: the physics of the episodes runs in parallel without the GIL; each worker calls its
  // own copy.deepcopy of the policy (a stateful policy must not see two episodes at once). Checked
  // here, so a policy that cannot be copied fails before any episode runs
  const unsigned workers = threads == 0 ? std::max(1U, std::thread::hardware_concurrency()) : static_cast<unsigned>(threads);
  // a Python method object: registered as a user method (kind "python") for this call only
  adapt::MethodRegistration method_registration;
  if (!method_object.is_none()) {
    method_registration = register_python_method(method_object, method_identity.cast<py::dict>(), workers);
    q.method.name = method_registration.name();
  }
  eval::JobSpec job = eval::resolve_job(q, resolver);
  // as run --robot/--package and --calibration: the robot's content hash and the calibration's hash
  // enter the job (and its id)
  if (robot) {
    const sim::RobotSource r = sim::load_robot_source(*robot, sim::parse_package_args(packages));
    job.robot = eval::RobotRef{r.sha256, r.urdf, r.packages};
  }
  eval::EpisodeFnOptions fn_options;
  if (!calibration.is_none()) {
    if (!job.calibration_sha256) throw InputError("evaluate", "calibration", "method " + job.method + " uses no response calibration");
    fn_options.calibration = resolve_calibration(calibration, task, profile);
    fn_options.calibration_source = py::isinstance<py::dict>(calibration) ? "calibration" : py::str(calibration).cast<std::string>();
    job.calibration_sha256 = fn_options.calibration->sha256();
  }
  if (workers > 1 && !builtin_backbone) {
    try {
      deepcopy(policy);
    } catch (py::error_already_set& e) {
      const std::string why = e.what();
      throw InputError("evaluate", "threads",
                       "each of the " + std::to_string(workers) + " workers needs copy.deepcopy(policy), which failed (" +
                           why.substr(0, why.find('\n')) + "); use threads=1");
    }
  }
  std::shared_ptr<const policy::Policy> prototype;
  if (builtin_backbone) {
    prototype = std::shared_ptr<const policy::Policy>(policy::make_policy(job.backbone.name, sim::parse_task(task)));
  } else {
    prototype = std::make_shared<PythonPolicy>(policy, job.backbone.name, job.backbone.sha256, sim::parse_task(task), workers > 1);
  }
  eval::RunOptions ro;
  ro.threads = workers;
  ro.out_dir = out;
  ro.progress = eval::parse_progress_mode(progress, "progress", "");
  // Ctrl-C: Python runs signal handlers only on the main thread, which waits inside run_job without
  // the GIL; the runner polls this hook there, so a KeyboardInterrupt stops the job (the finished
  // episodes are kept and the job resumes on the next call) and is raised here
  std::optional<py::error_already_set> signal_error;
  ro.interrupted = [&signal_error] {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() == 0) return false;
    signal_error.emplace();  // takes the pending exception (KeyboardInterrupt)
    return true;
  };
  eval::RunResult r;
  bool interrupted = false;
  {
    const eval::EpisodeFn fn = eval::make_episode_fn(job, prototype, fn_options);
    py::gil_scoped_release release;
    try {
      r = eval::run_job(job, fn, ro);
    } catch (const eval::Interrupted&) {
      interrupted = true;
    }
  }
  if (interrupted) {
    signal_error->restore();
    throw py::error_already_set();
  }
  py::dict d;
  d["job_id"] = r.job_id;
  d["jsonl_path"] = r.jsonl_path;
  d["summary_path"] = r.summary_path;
  d["episodes_total"] = r.episodes_total;
  d["episodes_before"] = r.episodes_before;
  d["episodes_run"] = r.episodes_run;
  d["already_complete"] = r.already_complete;
  d["wall_time_s"] = r.wall_time_s;
  d["job"] = json_to_py(eval::job_canonical_json(job));
  return d;
}

// ---------------------------------------------------------------- adapters

// an adapter by method name, with its task's calibration and (for pool methods) a pool
std::unique_ptr<adapt::Adapter> make_adapter(const std::string& label, const std::string& task, py::object pool,
                                             py::object truth, py::object params, py::object calibration) {
  (void)sim::parse_task(task);  // every method names a task, even those that do not read its calibration
  const std::string text =
      params.is_none() ? std::string("{}") : (py::isinstance<py::str>(params) ? params.cast<std::string>() : py_to_json(params, "params"));
  // a name or a variant label (entropy_probes{calibrated}), as on the command line
  const eval::MethodEntry entry = eval::canonical_method(eval::MethodEntry{label, text});
  const std::string& method = entry.name;
  const nlohmann::json p = adapt::resolve_method_params(method, parse_json_input(entry.params, "method " + method, "params"));
  struct Holder {
    std::vector<Contract> pool;
    std::optional<Contract> truth;
    std::optional<adapt::ResponseModel> model;
  } h;
  adapt::MethodInputs in;
  if (!pool.is_none()) {
    h.pool = to_contracts(pool, "pool");
    in.pool = &h.pool;
  }
  if (!truth.is_none()) {
    h.truth = to_contract(truth);
    in.truth = &*h.truth;
  }
  if (adapt::method_needs_calibration(method)) {
    if (calibration.is_none()) {
      h.model = eval::builtin_calibration(std::string(sim::task_name(sim::parse_task(task)))).model();
    } else if (py::isinstance<py::dict>(calibration)) {  // a calibration object, as `calibrate --json` writes it
      h.model = adapt::ResponseCalibration::from_json(py_to_json(calibration, "calibration"), "calibration").model();
    } else {  // a calibration file
      const std::string path = py::str(py::module_::import("os").attr("fspath")(calibration)).cast<std::string>();
      h.model = adapt::ResponseCalibration::load(path).model();
    }
    in.model = &*h.model;
  } else if (!calibration.is_none()) {
    throw InputError("method " + method, "calibration", "this method uses no response calibration");
  }
  return adapt::make_adapter(method, p, in);  // adapters copy what they keep
}

// where a task's observation holds the TCP pose, and the observation's length
struct ObsSlice {
  adapt::TcpSlice tcp;
  py::ssize_t size;
};

ObsSlice slice_of(const std::string& task) {
  const sim::ObservationLayout& layout = sim::observation_layout(sim::parse_task(task));
  return {eval::tcp_slice(layout), static_cast<py::ssize_t>(layout.size())};
}

// an observation of exactly the task's length: another task's observation (or any other vector)
// would be read at the wrong offsets without complaint
std::vector<double> obs_vector(py::handle h, const ObsSlice& s, const std::string& task, const char* what) {
  DArray a = as_array(h, what);
  if (a.ndim() != 1 || a.shape(0) != s.size)
    value_error(std::string(what) + ": not an observation of " + task + " (expected shape (" + std::to_string(s.size) +
                ",), got " + shape_of(a) + ")");
  if (!std::all_of(a.data(), a.data() + a.shape(0), [](double x) { return std::isfinite(x); }))
    value_error(std::string(what) + ": must be finite");
  const double* q = a.data() + s.tcp.quaternion_start;
  if (std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) < 1e-9)
    value_error(std::string(what) + ": its TCP quaternion is zero");
  return {a.data(), a.data() + a.shape(0)};
}

// ---------------------------------------------------------------- self-test

selftest::TcpPose to_tcp_pose(py::handle position, py::handle quaternion, py::handle fingers) {
  selftest::TcpPose p;
  p.position = to_vec<3>(position, "position");
  p.quaternion = to_vec<4>(quaternion, "quaternion");
  if (!fingers.is_none()) p.fingers = to_vec<2>(fingers, "fingers");
  return p;
}

class PySelfTest {
 public:
  PySelfTest(py::object expected, py::object pool, py::object model, const std::string& strategy, int budget,
             double amplitude, double confidence_floor, double misspec_ratio, const std::string& frame_rotation,
             const std::string& task, py::object gripper, py::object misspec_ratio_absolute)
      : task_(task) {
    selftest::Options o;
    // as on the command line: a library contract by name ("swapped-axes"), and "library" for the library pool
    if (py::isinstance<py::str>(expected)) {
      const std::string text = expected.cast<std::string>();
      if (const auto named = selftest::named_contract(text)) o.expected = *named;
      else if (text.find('{') == std::string::npos)
        throw InputError("expected", "", "unknown library contract '" + text + "' (known: " + selftest::named_contract_list() + ")");
      else o.expected = to_contract(expected);
    } else if (!expected.is_none()) {
      o.expected = to_contract(expected);
    }
    if (py::isinstance<py::str>(pool) && pool.cast<std::string>() == "library") {
      for (const auto& n : selftest::library()) o.pool.push_back(n.contract);
    } else if (!pool.is_none()) {
      o.pool = to_contracts(pool, "pool");
    }
    if (!model.is_none()) {
      if (py::isinstance<py::str>(model)) {
        o.model = eval::builtin_selftest_calibration(model.cast<std::string>()).model();
      } else {
        if (!py::isinstance<py::dict>(model) || !model.contains("alpha") || !model.contains("sigma"))
          throw py::type_error("model: expected a calibration name or a dict with 'alpha' and 'sigma' (6 numbers each)");
        const auto alpha = to_vec<kPoseDim>(model["alpha"], "model.alpha");
        const auto sigma = to_vec<kPoseDim>(model["sigma"], "model.sigma");
        std::copy(alpha.data(), alpha.data() + kPoseDim, o.model.alpha.begin());
        std::copy(sigma.data(), sigma.data() + kPoseDim, o.model.sigma.begin());
      }
    }
    if (strategy == "entropy") o.strategy = selftest::Strategy::kEntropy;
    else if (strategy == "fixed") o.strategy = selftest::Strategy::kFixed;
    else throw InputError("selftest options", "strategy", "expected 'entropy' or 'fixed' (got '" + strategy + "')");
    o.budget = budget;
    o.amplitude = amplitude;
    o.confidence_floor = confidence_floor;
    o.misspec_ratio = misspec_ratio;
    if (!misspec_ratio_absolute.is_none()) {  // the threshold for absolute-target wirings (default: misspec_ratio)
      if (!py::isinstance<py::float_>(misspec_ratio_absolute) && !py::isinstance<py::int_>(misspec_ratio_absolute))
        throw py::type_error("misspec_ratio_absolute: expected a number or None");
      o.misspec_ratio_absolute = misspec_ratio_absolute.cast<double>();
    }
    o.frame_rotation = parse_rotation_mode(frame_rotation, "selftest options", "frame_rotation");
    if (!gripper.is_none()) {  // (offset, gain): the probes hold the fingers (selftest::Options::gripper)
      const auto g = to_vec<2>(gripper, "gripper");
      o.gripper = selftest::GripperMap{g[0], g[1]};
    }
    std::string err;
    auto st = selftest::SelfTest::create(o, &err);
    if (!st) throw std::invalid_argument(err);
    st_ = std::make_unique<selftest::SelfTest>(std::move(*st));
  }
  void begin(py::handle position, py::handle quaternion, py::handle fingers) {
    st_->begin(to_tcp_pose(position, quaternion, fingers));
  }
  py::object next_probe() {
    const auto p = st_->next_probe();
    if (!p) return py::none();
    return vec_out(*p);
  }
  void observe(py::handle position, py::handle quaternion, py::handle fingers) {
    st_->observe(to_tcp_pose(position, quaternion, fingers));
  }
  bool done() const { return st_->done(); }
  int probes_observed() const { return st_->probes_observed(); }
  std::vector<Contract> pool() const { return st_->pool(); }
  DArray posterior() const { return vec_out(st_->posterior()); }
  selftest::ReportHeader header() const {
    selftest::ReportHeader h;
    h.task = task_;
    h.backend = "python";
    h.strategy = selftest::to_string(st_->options().strategy);
    h.budget = st_->options().budget;
    h.pool_size = static_cast<int>(st_->pool().size());
    return h;
  }
  py::object verdict() const { return json_to_py(selftest::to_json(st_->verdict(), header())); }
  std::string report() const { return selftest::to_text(st_->verdict(), header()); }

 private:
  std::string task_;
  std::unique_ptr<selftest::SelfTest> st_;
};

// ---------------------------------------------------------------- manifests

py::dict check_dict(const Check& c) {
  py::dict d;
  d["name"] = c.name;
  d["ok"] = c.ok;
  d["detail"] = c.detail;
  return d;
}

}  // namespace

PYBIND11_MODULE(_native, m) {
  m.doc() = "ActionShift native core (use the `actionshift` package)";

  // errors: InputError -> actionshift.InputError (a ValueError) with the one-line message and its parts
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      py::object exc = py::handle(input_error.ptr())(e.what());
      exc.attr("source") = e.source();
      exc.attr("field") = e.field();
      exc.attr("reason") = e.reason();
      PyErr_SetObject(input_error.ptr(), exc.ptr());
    }
  });

  // ---- contracts and the core
  py::class_<Contract>(m, "Contract", "An immutable action contract (see docs/splits.md).")
      .def(py::init(&make_contract),
           py::arg("permutation") = std::vector<long long>{0, 1, 2, 3, 4, 5},
           py::arg("sign") = std::vector<long long>{1, 1, 1, 1, 1, 1},
           py::arg("scale") = std::vector<double>{1, 1, 1, 1, 1, 1}, py::arg("target") = "delta",
           py::arg("frame") = "base", py::arg("lag") = 0, py::arg("gripper_inverted") = false)
      .def(py::init([](const py::args& args, const py::kwargs& kwargs) {
        const auto v = bind_call(
            "Contract",
            {{"permutation", "a sequence of 6 integers", &castable<std::vector<long long>>, py::cast(std::vector<long long>{0, 1, 2, 3, 4, 5})},
             {"sign", "a sequence of 6 integers (+1 or -1)", &castable<std::vector<long long>>, py::cast(std::vector<long long>{1, 1, 1, 1, 1, 1})},
             {"scale", "a sequence of 6 numbers", &castable<std::vector<double>>, py::cast(std::vector<double>{1, 1, 1, 1, 1, 1})},
             {"target", "a str", &castable<std::string>, py::str("delta")},
             {"frame", "a str", &castable<std::string>, py::str("base")},
             {"lag", "an int", &castable<long long>, py::int_(0)},
             {"gripper_inverted", "a bool", &castable<bool>, py::bool_(false)}},
            args, kwargs);
        return make_contract(v[0].cast<std::vector<long long>>(), v[1].cast<std::vector<long long>>(),
                             v[2].cast<std::vector<double>>(), v[3].cast<std::string>(), v[4].cast<std::string>(),
                             v[5].cast<long long>(), v[6].cast<bool>());
      }))
      .def_static("identity", &Contract::identity)
      .def_static("from_json", [](py::handle h) { return to_contract(h); }, py::arg("json"),
                  "From JSON text or a dict; raises ValueError (actionshift.InputError) with the reason.")
      .def("to_json", &Contract::to_json, "Canonical JSON (the hash input).")
      .def("to_dict", [](const Contract& c) { return json_to_py(c.to_json()); })
      .def("hash", &Contract::sha256, "Lowercase hex SHA-256 of the canonical JSON (= `actionshift contract hash`).")
      .def_property_readonly("sha256", &Contract::sha256)
      .def_property_readonly("permutation", &Contract::permutation)
      .def_property_readonly("sign", &Contract::sign)
      .def_property_readonly("scale", &Contract::scale)
      .def_property_readonly("target", [](const Contract& c) { return std::string(to_string(c.target())); })
      .def_property_readonly("frame", [](const Contract& c) { return std::string(to_string(c.frame())); })
      .def_property_readonly("lag", &Contract::lag)
      .def_property_readonly("gripper_inverted", &Contract::gripper_inverted)
      .def("composition_signature", &Contract::composition_signature)
      .def("__eq__", [](const Contract& a, const Contract& b) { return a == b; })
      .def("__hash__", [](const Contract& c) { return py::hash(py::str(c.sha256())); })
      .def("__repr__", [](const Contract& c) { return "Contract.from_json('" + c.to_json() + "')"; });

  m.def("decode", [](py::handle c, py::handle raw, py::handle R, py::handle target) {
        return vec_out(decode(to_contract(c), to_vec<kActionDim>(raw, "raw"), to_rotation(R, "R"), to_target(target)));
      }, py::arg("contract"), py::arg("raw"), py::arg("R") = py::none(), py::arg("tracked_target") = py::none(),
      "Canonical action (7) that a raw action decodes to (stateless; lag is the Decoder's).");
  m.def("encode", [](py::handle c, py::handle canonical, py::handle R, py::handle target) {
        return vec_out(encode(to_contract(c), to_vec<kActionDim>(canonical, "canonical"), to_rotation(R, "R"), to_target(target)));
      }, py::arg("contract"), py::arg("canonical"), py::arg("R") = py::none(), py::arg("tracked_target") = py::none(),
      "Raw action (7) that decodes to `canonical` (the inverse of decode).");
  m.def("decode_jacobian", [](py::handle c, py::handle R) {
        const ActionJacobian J = decode_jacobian(to_contract(c), to_rotation(R, "R"));
        DArray out({kActionDim, kActionDim});
        for (int i = 0; i < kActionDim; ++i)
          for (int j = 0; j < kActionDim; ++j) out.mutable_at(i, j) = J(i, j);
        return out;
      }, py::arg("contract"), py::arg("R") = py::none());
  m.def("pool_sha256", [](py::handle contracts) { return pool_sha256(to_contracts(contracts, "contracts")); },
        py::arg("contracts"));

  py::class_<Decoder>(m, "Decoder", "Stateful decoder (tracked target + lag FIFO) over num_envs environments.")
      .def(py::init([](py::handle c, py::handle num_envs) {
             const auto n = to_int(num_envs, "num_envs", 1, std::numeric_limits<int>::max());
             return Decoder(to_contract(c), static_cast<int>(n));
           }), py::arg("contract"),
           py::arg("num_envs") = 1)
      .def_property_readonly("contract", &Decoder::contract)
      .def_property_readonly("num_envs", &Decoder::num_envs)
      .def("reset", [](Decoder& d, std::optional<int> env) {
             if (env) d.reset(*env);
             else d.reset_all();
           }, py::arg("env") = py::none())
      .def("tracked_target", [](const Decoder& d, int env) { return vec_out(d.tracked_target(env)); }, py::arg("env") = 0)
      .def("step", [](Decoder& d, py::handle raw, py::handle R, bool reset) {
             return vec_out(d.step(to_vec<kActionDim>(raw, "raw"), to_rotation(R, "R"), reset));
           }, py::arg("raw"), py::arg("R") = py::none(), py::arg("reset") = false,
           "One environment: the canonical action handed to the controller (after the lag FIFO).")
      .def("step_batch", [](Decoder& d, py::handle raw, py::handle R, py::handle reset_mask) {
             DArray a = as_array(raw, "raw");
             const int n = d.num_envs();
             if (a.ndim() != 2 || a.shape(0) != n || a.shape(1) != kActionDim)
               value_error("raw: must have shape (" + std::to_string(n) + ", 7) (got " + shape_of(a) + ")");
             Decoder::Batch in(kActionDim, n), out(kActionDim, n);
             for (int e = 0; e < n; ++e)
               for (int k = 0; k < kActionDim; ++k) in(k, e) = a.at(e, k);
             std::vector<Mat3> rs;
             if (!R.is_none()) {
               DArray r = as_array(R, "R");
               if (r.ndim() == 2) rs.push_back(to_rotation(r, "R"));
               else if (r.ndim() == 3 && r.shape(0) == n) {
                 for (int e = 0; e < n; ++e) rs.push_back(to_rotation(r[py::int_(e)], "R"));
               } else value_error("R: must be None, 3x3 or (" + std::to_string(n) + ", 3, 3) (got " + shape_of(r) + ")");
             }
             std::unique_ptr<bool[]> mask;
             std::span<const bool> mask_span;
             if (!reset_mask.is_none()) {
               std::vector<bool> v;
               try {
                 v = reset_mask.cast<std::vector<bool>>();
               } catch (const py::cast_error&) {
                 value_error("reset_mask: must be " + std::to_string(n) + " booleans");
               }
               if (static_cast<int>(v.size()) != n) value_error("reset_mask: must have " + std::to_string(n) + " flags");
               mask = std::make_unique<bool[]>(v.size());
               std::copy(v.begin(), v.end(), mask.get());
               mask_span = {mask.get(), v.size()};
             }
             d.step(in, rs, mask_span, out);
             DArray res({n, kActionDim});
             for (int e = 0; e < n; ++e)
               for (int k = 0; k < kActionDim; ++k) res.mutable_at(e, k) = out(k, e);
             return res;
           }, py::arg("raw"), py::arg("R") = py::none(), py::arg("reset_mask") = py::none(),
           "All environments: raw (N, 7) -> canonical (N, 7).")
      .def("preview", [](const Decoder& d, py::handle raw, py::handle R, int env) {
             return vec_out(d.preview(to_vec<kActionDim>(raw, "raw"), to_rotation(R, "R"), env));
           }, py::arg("raw"), py::arg("R") = py::none(), py::arg("env") = 0);

  // ---- manifests and pools
  py::class_<Manifest>(m, "Manifest", "A split manifest or contract pool (docs/splits.md).")
      .def_property_readonly("name", &Manifest::name)
      .def_property_readonly("kind", [](const Manifest& x) { return std::string(x.is_pool() ? "pool" : "split"); })
      .def_property_readonly("rule", &Manifest::rule)
      .def_property_readonly("seed", &Manifest::seed)
      .def_property_readonly("description", &Manifest::description)
      .def_property_readonly("generator_version", &Manifest::generator_version)
      .def_property_readonly("contracts", &Manifest::contracts, "Evaluation contracts (split) or members (pool), in order.")
      .def_property_readonly("train", &Manifest::train_contracts)
      .def_property_readonly("manifest_sha256", &Manifest::manifest_sha256, "The hash written in the file.")
      .def("computed_sha256", &Manifest::computed_sha256, "The hash of the body as it is (validate compares the two).")
      .def_property_readonly("pool_sha256", [](const Manifest& x) -> py::object {
        if (!x.is_pool()) return py::none();
        return py::str(x.pool_sha256());
      })
      .def("validate", [](const Manifest& x, bool regenerate) {
             py::list out;
             for (const auto& c : validate(x, regenerate)) out.append(check_dict(c));
             return out;
           }, py::arg("regenerate") = true, "The checks of `actionshift validate` for this manifest.")
      .def("__len__", [](const Manifest& x) { return x.test().size(); })
      .def("__repr__", [](const Manifest& x) {
        return "<actionshift.Manifest " + x.name() + " (" + (x.is_pool() ? "pool" : "split") + ", " +
               std::to_string(x.test().size()) + " contracts)>";
      });
  m.def("load_manifest", &data::resolve_manifest, py::arg("name_or_path"),
        "A manifest file, or a built-in split or pool by name.");
  m.def("builtin_manifests", &data::builtin_manifest_names);

  // ---- environments
  py::class_<PyEnv>(m, "_Env")
      .def(py::init([](const std::string& task, py::handle contract, std::optional<std::string> split, std::int64_t index,
                       const std::string& rotation, const std::string& profile, std::optional<std::string> robot,
                       std::vector<std::string> packages, double obs_noise, bool ignore_terminations,
                       std::optional<std::tuple<int, int, std::string>> render) {
             EnvOptions o{task, rotation, profile, std::move(robot), std::move(packages), obs_noise, ignore_terminations};
             std::optional<RenderSetup> r;
             if (render) r = RenderSetup{std::get<0>(*render), std::get<1>(*render), std::get<2>(*render)};
             return std::make_unique<PyEnv>(o, contract, std::move(split), index, r);
           }),
           py::arg("task"), py::arg("contract"), py::arg("split"), py::arg("index"), py::arg("rotation"), py::arg("profile"),
           py::arg("robot"), py::arg("packages"), py::arg("obs_noise"), py::arg("ignore_terminations"), py::arg("render"))
      .def("reset", &PyEnv::reset, py::arg("seed") = py::none())
      .def("step", &PyEnv::step, py::arg("action"))
      .def("render", &PyEnv::render)
      .def("close", &PyEnv::close)
      .def_property("last_seed", &PyEnv::last_seed, &PyEnv::set_last_seed)
      .def_property_readonly("task", &PyEnv::task)
      .def_property_readonly("horizon", &PyEnv::horizon)
      .def_property_readonly("obs_dim", &PyEnv::obs_dim)
      .def_property_readonly("layout", &PyEnv::layout)
      .def_property_readonly("profile", &PyEnv::profile)
      .def_property_readonly("rotation", &PyEnv::rotation)
      .def_property_readonly("robot_sha256", &PyEnv::robot_sha256);
  py::class_<PyVecEnv>(m, "_VecEnv")
      .def(py::init([](const std::string& task, int num_envs, py::handle contract, std::optional<std::string> split,
                       std::int64_t index, const std::string& rotation, const std::string& profile, unsigned threads,
                       std::optional<std::string> robot, std::vector<std::string> packages, double obs_noise,
                       bool ignore_terminations) {
             EnvOptions o{task, rotation, profile, std::move(robot), std::move(packages), obs_noise, ignore_terminations};
             return std::make_unique<PyVecEnv>(o, num_envs, contract, std::move(split), index, threads);
           }),
           py::arg("task"), py::arg("num_envs"), py::arg("contract"), py::arg("split"), py::arg("index"),
           py::arg("rotation"), py::arg("profile"), py::arg("threads"), py::arg("robot"), py::arg("packages"),
           py::arg("obs_noise"), py::arg("ignore_terminations"))
      .def("reset", &PyVecEnv::reset, py::arg("seed") = py::none())
      .def("step", &PyVecEnv::step, py::arg("actions"))
      .def("close", &PyVecEnv::close)
      .def_property("last_seed", &PyVecEnv::last_seed, &PyVecEnv::set_last_seed)
      .def_property_readonly("num_envs", &PyVecEnv::num_envs)
      .def_property_readonly("obs_dim", &PyVecEnv::obs_dim)
      .def_property_readonly("horizon", &PyVecEnv::horizon)
      .def_property_readonly("threads", &PyVecEnv::threads)
      .def_property_readonly("robot_sha256", &PyVecEnv::robot_sha256);
  m.def("write_frames", &write_frames, py::arg("path"), py::arg("frames"), py::arg("delay_cs"), py::arg("frame"));
  m.def("episode_seed", [](py::handle seed, py::handle contract_episode) {
    return eval::episode_seed(to_seed(seed, "seed"), to_int(contract_episode, "contract_episode", 0, std::int64_t{1} << 62));
  }, py::arg("seed"), py::arg("contract_episode"),
        "The environment seed of a job's episode (the runner's episode_seed): every contract's episode k starts from it.");
  m.def("_load_calibration", &load_calibration, py::arg("calibration"), py::arg("task"), py::arg("profile"));
  m.attr("__version__") = eval::build_provenance().version;
  m.attr("__git_commit__") = eval::build_provenance().git_commit.empty() ? py::object(py::none()) : py::object(py::str(eval::build_provenance().git_commit));
  // the statistics engine's Wilson score interval (core/wilson.hpp), for pages laid out in Python
  m.def(
      "wilson_interval",
      [](std::int64_t successes, std::int64_t total) {
        if (total <= 0 || successes < 0 || successes > total)
          value_error("wilson_interval: need 0 <= successes <= total and total > 0 (got " + std::to_string(successes) + " of " +
                      std::to_string(total) + ")");
        return json_to_py(eval::wilson_json(wilson_interval(successes, total)).dump());
      },
      py::arg("successes"), py::arg("total"),
      "Wilson score 95 % interval of successes/total, as Gate 0 and compare compute it (not clamped).");
  m.def("tasks", [] {
    std::vector<std::string> out;
    for (auto t : sim::all_tasks()) out.emplace_back(sim::task_name(t));
    return out;
  });
  m.def("_task_maniskill_ids", [] {  // (name, ManiSkill id) of every task, from its description
    std::vector<std::pair<std::string, std::string>> out;
    for (auto t : sim::all_tasks()) out.emplace_back(sim::task_name(t), sim::task_description(t).maniskill_id);
    return out;
  });
  m.def("_bench_cpp_steps", &bench_cpp_steps, py::arg("task"), py::arg("actions"), py::arg("seed"),
        py::arg("profile") = "maniskill");
  m.def("_bench_policy_calls", &bench_policy_calls, py::arg("policy"), py::arg("command"), py::arg("task"),
        py::arg("calls"));
  m.attr("MAX_NUM_ENVS") = kMaxNumEnvs;
  m.def("env_config_check", [](const std::string& profile) { env_config_for_profile(profile); }, py::arg("profile"));

  // ---- adapters
  py::class_<adapt::Adapter>(m, "Adapter", "An adapter: begin_episode / encode / observe (docs/adapters.md).")
      .def_property_readonly("name", &adapt::Adapter::name)
      .def("begin_episode", [](adapt::Adapter& a, py::handle seed) { a.begin_episode(to_seed(seed, "episode_seed")); },
           py::arg("episode_seed"))
      .def("encode", [](adapt::Adapter& a, py::handle canonical, py::handle R) {
             const Action c = to_vec<kActionDim>(canonical, "canonical");
             if (!c.allFinite()) value_error("canonical: must be finite (it holds NaN or inf)");
             return vec_out(a.encode(c, to_rotation(R, "R")));
           }, py::arg("canonical"), py::arg("R") = py::none())
      .def("observe", [](adapt::Adapter& a, py::handle raw, py::handle response, py::handle R) {
             a.observe(to_vec<kActionDim>(raw, "raw"), to_vec<kPoseDim>(response, "response"), to_rotation(R, "R"));
           }, py::arg("raw"), py::arg("response"), py::arg("R") = py::none())
      .def_property_readonly("last_probe", [](const adapt::Adapter& a) { return a.last_step().probe; })
      .def_property_readonly("last_task_regret", [](const adapt::Adapter& a) { return a.last_step().task_regret; });
  m.def("_make_adapter", &make_adapter, py::arg("method"), py::arg("task"), py::arg("pool"), py::arg("truth"),
        py::arg("params"), py::arg("calibration"));
  m.def("methods", &adapt::method_names);
  m.def("method_needs_pool", &adapt::method_needs_pool, py::arg("method"));
  m.def("method_needs_calibration", &adapt::method_needs_calibration, py::arg("method"));
  m.def("method_params", [](const std::string& method, py::object params) {
        return json_to_py(eval::resolved_method_params(method, params.is_none() ? "{}" : py_to_json(params, "params")));
      }, py::arg("method"), py::arg("params") = py::none(),
        "The method's parameters with every default filled in (the paper's method); `method` may be a variant label.");
  m.def("method_label", [](const std::string& method, py::object params) {
        const eval::MethodEntry e = eval::canonical_method(eval::MethodEntry{method, params.is_none() ? "{}" : py_to_json(params, "params")});
        return adapt::method_variant_label(e.name, adapt::resolve_method_params(e.name, parse_json_input(e.params, "method " + e.name, "params")));
      }, py::arg("method"), py::arg("params") = py::none(),
        "The canonical variant label records and summary cells carry: 'entropy_probes' (the paper's method), "
        "'entropy_probes{calibrated}', 'dualabi{tau=0.5}'.");
  m.def("method_variants", [] {
        py::list out;
        for (const auto& v : adapt::method_variants())
          out.append(py::dict(py::arg("method") = v.method, py::arg("name") = v.name, py::arg("params") = json_to_py(canonical_dump(v.params)),
                              py::arg("rationale") = v.rationale));
        return out;
      }, "The named method variants: method, name, the parameters they set, and why they exist.");
  m.def("tcp_rotation", [](py::handle obs, const std::string& task) {
        const auto s = slice_of(task);
        return mat_out(adapt::tcp_rotation(obs_vector(obs, s, task, "obs"), s.tcp));
      }, py::arg("obs"), py::arg("task"), "The TCP orientation in an observation (the R adapters take under `live`).");
  m.def("tcp_response", [](py::handle prev, py::handle cur, const std::string& task) {
        const auto s = slice_of(task);
        return vec_out(adapt::tcp_response(obs_vector(prev, s, task, "prev_obs"), obs_vector(cur, s, task, "obs"), s.tcp));
      }, py::arg("prev_obs"), py::arg("obs"), py::arg("task"), "The TCP response (6) between two observations.");

  // ---- evaluation
  py::class_<adapt::ResponseModel>(m, "ResponseModel",
                                   "A task's calibrated response model: response_c ~ alpha_c * canonical_c, noise sigma_c "
                                   "(docs/reference.md); what the pool and grammar rungs receive.")
      .def(py::init([](py::handle alpha, py::handle sigma, double gripper_alpha, double gripper_sigma) {
             adapt::ResponseModel r;
             const auto a = to_vec<kPoseDim>(alpha, "alpha");
             const auto s = to_vec<kPoseDim>(sigma, "sigma");
             for (int c = 0; c < kPoseDim; ++c) {
               r.alpha[static_cast<std::size_t>(c)] = a[c];
               r.sigma[static_cast<std::size_t>(c)] = s[c];
             }
             r.gripper_alpha = gripper_alpha;
             r.gripper_sigma = gripper_sigma;
             try {
               r.validate();
             } catch (const std::invalid_argument& e) {
               value_error(std::string("ResponseModel: ") + e.what());
             }
             return r;
           }), py::arg("alpha"), py::arg("sigma"), py::arg("gripper_alpha") = 0.0, py::arg("gripper_sigma") = 0.0)
      .def_property_readonly("alpha", [](const adapt::ResponseModel& r) { return vec_out(r.alpha); })
      .def_property_readonly("sigma", [](const adapt::ResponseModel& r) { return vec_out(r.sigma); })
      .def_readonly("gripper_alpha", &adapt::ResponseModel::gripper_alpha)
      .def_readonly("gripper_sigma", &adapt::ResponseModel::gripper_sigma)
      .def("__repr__", [](const adapt::ResponseModel& r) {
        std::ostringstream s;
        s << "ResponseModel(alpha=[" << r.alpha[0] << ", ...], sigma=[" << r.sigma[0] << ", ...])";
        return s.str();
      });
  py::class_<adapt::PoolBelief>(m, "PoolBelief",
                                "Exact Bayesian belief over a pool of contracts (docs/adapters.md, Pool belief): one "
                                "decoder replica per hypothesis, the calibrated Gaussian likelihood, MAP encoding.")
      .def(py::init([](py::handle pool, const adapt::ResponseModel& model) {
             return adapt::PoolBelief(to_contracts(pool, "pool"), model);
           }), py::arg("pool"), py::arg("calibration"))
      .def_property_readonly("size", &adapt::PoolBelief::size)
      .def_property_readonly("pool", &adapt::PoolBelief::pool)
      .def("reset", &adapt::PoolBelief::reset, "Uniform belief and fresh replicas (the start of an episode).")
      .def("update", [](adapt::PoolBelief& b, py::handle raw, py::handle response, py::handle R) {
             b.update(to_vec<kActionDim>(raw, "raw"), to_vec<kPoseDim>(response, "response"), to_rotation(R, "R"));
           }, py::arg("raw"), py::arg("response"), py::arg("R") = py::none())
      .def_property_readonly("log_probs", [](const adapt::PoolBelief& b) { return vec_out(b.log_probs()); })
      .def("probs", [](const adapt::PoolBelief& b) { return vec_out(b.probs()); })
      .def("entropy", &adapt::PoolBelief::entropy)
      .def("map_index", &adapt::PoolBelief::map_index)
      .def("map_encode", [](const adapt::PoolBelief& b, py::handle canonical, py::handle R) {
             return vec_out(b.map_encode(to_vec<kActionDim>(canonical, "canonical"), to_rotation(R, "R")));
           }, py::arg("canonical"), py::arg("R") = py::none())
      .def("encode_with", [](const adapt::PoolBelief& b, int h, py::handle canonical, py::handle R) {
             if (h < 0 || h >= b.size()) value_error("h: must be in [0, " + std::to_string(b.size()) + ")");
             return vec_out(b.encode_with(h, to_vec<kActionDim>(canonical, "canonical"), to_rotation(R, "R")));
           }, py::arg("h"), py::arg("canonical"), py::arg("R") = py::none())
      .def("preview", [](const adapt::PoolBelief& b, py::handle raw, py::handle R, bool lag_aware) {
             std::vector<Action> out;
             b.preview(to_vec<kActionDim>(raw, "raw"), to_rotation(R, "R"), lag_aware, out);
             DArray a({static_cast<py::ssize_t>(out.size()), static_cast<py::ssize_t>(kActionDim)});
             for (std::size_t h = 0; h < out.size(); ++h)
               for (int c = 0; c < kActionDim; ++c) a.mutable_at(static_cast<py::ssize_t>(h), c) = out[h][c];
             return a;
           }, py::arg("raw"), py::arg("R") = py::none(), py::arg("lag_aware") = true,
           "The canonical action each hypothesis would decode from `raw` now (rows: hypotheses), without changing state.");
  m.def("method_rung", [](const std::string& method) { return std::string(adapt::rung_name(adapt::method_rung(method))); },
        py::arg("method"));
  m.def("_evaluate", &evaluate, py::arg("policy"), py::arg("task"), py::arg("split"), py::arg("method"), py::arg("seed"),
        py::arg("episodes"), py::arg("out"), py::arg("backbone"), py::arg("pool"), py::arg("params"),
        py::arg("rotation"), py::arg("profile"), py::arg("progress"), py::arg("threads"), py::arg("method_object") = py::none(),
        py::arg("method_identity") = py::none(), py::arg("backbone_sha256") = py::none(),
        py::arg("robot") = py::none(), py::arg("packages") = std::vector<std::string>{}, py::arg("obs_noise") = 0.0,
        py::arg("calibration") = py::none(), py::arg("horizon") = 0);
  m.def("job_id", [](py::handle spec) { return eval::job_id(eval::job_from_json(nlohmann::json::parse(py_to_json(spec, "job")), "job")); },
        py::arg("job"));

  // ---- self-test
  py::class_<PySelfTest>(m, "SelfTest", "Plug-and-verify with the control loop inverted (docs/selftest.md).")
      .def(py::init<py::object, py::object, py::object, const std::string&, int, double, double, double,
                    const std::string&, const std::string&, py::object, py::object>(),
           py::arg("expected") = py::none(), py::arg("pool") = py::none(), py::arg("model") = py::none(),
           py::arg("strategy") = "entropy", py::arg("budget") = 6, py::arg("amplitude") = 0.5,
           py::arg("confidence_floor") = 0.9, py::arg("misspec_ratio") = 4.0, py::arg("frame_rotation") = "live",
           py::arg("task") = "custom", py::arg("gripper") = py::none(), py::arg("misspec_ratio_absolute") = py::none())
      .def(py::init([](const py::args& args, const py::kwargs& kwargs) {
        const auto v = bind_call("SelfTest",
                                 {{"expected", "a contract", &castable<py::object>, py::none()},
                                  {"pool", "a pool", &castable<py::object>, py::none()},
                                  {"model", "a response model", &castable<py::object>, py::none()},
                                  {"strategy", "a str", &castable<std::string>, py::str("entropy")},
                                  {"budget", "an int", &castable<int>, py::int_(6)},
                                  {"amplitude", "a number", &castable<double>, py::float_(0.5)},
                                  {"confidence_floor", "a number", &castable<double>, py::float_(0.9)},
                                  {"misspec_ratio", "a number", &castable<double>, py::float_(4.0)},
                                  {"frame_rotation", "a str", &castable<std::string>, py::str("live")},
                                  {"task", "a str", &castable<std::string>, py::str("custom")},
                                  {"gripper", "a gripper description", &castable<py::object>, py::none()},
                                  {"misspec_ratio_absolute", "a number or None", &castable<py::object>, py::none()}},
                                 args, kwargs);
        return std::make_unique<PySelfTest>(v[0], v[1], v[2], v[3].cast<std::string>(), v[4].cast<int>(),
                                            v[5].cast<double>(), v[6].cast<double>(), v[7].cast<double>(),
                                            v[8].cast<std::string>(), v[9].cast<std::string>(), v[10], v[11]);
      }))
      .def("begin", &PySelfTest::begin, py::arg("position"), py::arg("quaternion"), py::arg("fingers") = py::none())
      .def("next_probe", &PySelfTest::next_probe, "The next raw 7-vector to send, or None once the budget is spent.")
      .def("observe", &PySelfTest::observe, py::arg("position"), py::arg("quaternion"), py::arg("fingers") = py::none())
      .def_property_readonly("done", &PySelfTest::done)
      .def_property_readonly("probes_observed", &PySelfTest::probes_observed)
      .def_property_readonly("pool", &PySelfTest::pool)
      .def("posterior", &PySelfTest::posterior)
      .def("verdict", &PySelfTest::verdict, "The verdict as a dict (the JSON report of `actionshift selftest --json`).")
      .def("report", &PySelfTest::report, "The human report.");
  m.def(
      "selftest_sim_options",
      [](const std::string& task) {
        (void)sim::parse_task(task);
        // what `actionshift selftest --sim --task T` sets: the library and reference9 pools (first
        // occurrence kept), the task's self-test calibration, probes that hold the fingers, and the
        // misspecification thresholds measured on the simulator (configs/selftest/sim_misspec.json)
        py::list pool;
        std::vector<Contract> seen;
        const auto add = [&](const Contract& c) {
          if (std::find(seen.begin(), seen.end(), c) != seen.end()) return;
          seen.push_back(c);
          pool.append(c);
        };
        for (const auto& n : selftest::library()) add(n.contract);
        for (const auto& c : data::resolve_manifest("reference9").contracts()) add(c);
        py::dict d;
        d["pool"] = pool;
        d["model"] = task;
        d["task"] = task;
        d["gripper"] = py::make_tuple(sim::kFingerTargetOffset, sim::kFingerTargetGain);
        d["budget"] = 6;
        d["amplitude"] = 0.5;
        const auto delta = data::builtin_selftest_misspec_ratio(task, "delta");
        const auto absolute = data::builtin_selftest_misspec_ratio(task, "absolute");
        d["misspec_ratio"] = delta ? *delta : 4.0;
        d["misspec_ratio_absolute"] = delta && absolute ? py::cast(*absolute) : py::none();
        return d;
      },
      py::arg("task"),
      "Keyword arguments of SelfTest that reproduce `actionshift selftest --sim --task TASK` when its probes\n"
      "drive make(TASK, contract=...): SelfTest(expected=..., **selftest_sim_options(TASK)).");
  m.def("selftest_library", [] {
    std::vector<std::pair<std::string, Contract>> out;
    for (const auto& n : selftest::library()) out.emplace_back(n.name, n.contract);
    return out;
  });
  // the log audit (docs/audit.md); actionshift.audit() in __init__.py shapes arrays or an .npz into episodes
  m.def(
      "_audit",
      [](py::list episodes, const std::string& declared, py::object model, double floor, double misspec, double gain_tolerance,
         bool has_gripper, const std::string& source) {
        using Arr = py::array_t<double, py::array::c_style | py::array::forcecast>;
        selftest::ActionLog log;
        log.source = source;
        log.layout = "arrays";
        log.has_gripper = has_gripper;
        for (std::size_t e = 0; e < episodes.size(); ++e) {
          const auto t = episodes[e].cast<py::tuple>();
          const std::string where = "episode " + std::to_string(e);
          const Arr a = Arr::ensure(t[0]), p = Arr::ensure(t[1]), q = Arr::ensure(t[2]);
          if (!a || a.ndim() != 2 || (a.shape(1) != 6 && a.shape(1) != 7)) throw InputError(source, where + ": actions", "must be an N x 6 or N x 7 array");
          if (!p || p.ndim() != 2 || p.shape(1) != 3) throw InputError(source, where + ": tcp_pos", "must be an N x 3 array");
          if (!q || q.ndim() != 2 || q.shape(1) != 4) throw InputError(source, where + ": tcp_quat", "must be an N x 4 array (w, x, y, z)");
          if (p.shape(0) != q.shape(0)) throw InputError(source, where + ": tcp_quat", "rows differ from tcp_pos's");
          // no fingers: the gripper's polarity is not checked (as for a CSV log without finger columns).
          // Not a default-constructed array_t: that is an empty 1-D array, which tests true.
          std::optional<Arr> f;
          if (!t[3].is_none()) {
            f = Arr::ensure(t[3]);
            if (!*f || f->ndim() != 2 || f->shape(1) != 2 || f->shape(0) != p.shape(0)) throw InputError(source, where + ": fingers", "must be an N x 2 array with tcp_pos's rows");
          }
          selftest::LogEpisode ep;
          for (py::ssize_t r = 0; r < a.shape(0); ++r) {
            Action x = Action::Zero();
            for (py::ssize_t k = 0; k < a.shape(1); ++k) x[static_cast<Eigen::Index>(k)] = a.at(r, k);
            ep.actions.push_back(x);
          }
          for (py::ssize_t r = 0; r < p.shape(0); ++r) {
            selftest::TcpPose pose;
            pose.position = Vec3(p.at(r, 0), p.at(r, 1), p.at(r, 2));
            pose.quaternion = Eigen::Vector4d(q.at(r, 0), q.at(r, 1), q.at(r, 2), q.at(r, 3));
            if (f) pose.fingers = Eigen::Vector2d(f->at(r, 0), f->at(r, 1));
            ep.poses.push_back(pose);
          }
          log.episodes.push_back(std::move(ep));
        }
        selftest::AuditOptions o;
        if (!declared.empty() && declared.front() == '{') {
          o.declared = selftest::Conventions::from_json_value(parse_json_input(declared, "declared"), "declared");
        } else if (auto c = selftest::named_contract(declared)) {
          o.declared.contract = *c;
        } else {
          throw InputError("declared", "", "unknown library contract " + quote_input(declared) + " (known: " + selftest::named_contract_list() + ")");
        }
        if (py::isinstance<py::str>(model)) o.model = eval::builtin_calibration(model.cast<std::string>()).model();
        else if (!model.is_none()) o.model = model.cast<adapt::ResponseModel>();
        o.confidence_floor = floor;
        o.misspec_ratio = misspec;
        o.gain_tolerance = gain_tolerance;
        if (const std::string err = selftest::validate(o); !err.empty()) throw InputError("audit options", "", err);
        return json_to_py(selftest::to_json(selftest::audit(log, o)));
      },
      py::arg("episodes"), py::arg("declared"), py::arg("model"), py::arg("confidence_floor"), py::arg("misspec_ratio"),
      py::arg("gain_tolerance"), py::arg("has_gripper"), py::arg("source"));
}
