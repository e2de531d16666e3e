// HDF5 logs for the audit: ManiSkill's and robomimic's layouts. The only translation unit that
// includes HDF5. HDF5's C API (not the C++ wrapper Debian also ships): its error stack can be
// silenced and every failure turned into our one-line InputError, and the C library is what every
// HDF5 installation has.
#include "actionshift/selftest/audit_hdf5.hpp"

#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/weight_file.hpp"

#include <hdf5.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>

namespace actionshift::selftest {

namespace {

// HDF5 prints its error stack to stderr by default; we report our own one-line errors instead
void silence_hdf5() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

bool exists(hid_t loc, const std::string& path) {
  // every intermediate link must exist before H5Lexists may be asked about the next one
  std::size_t start = 0;
  while (true) {
    const std::size_t slash = path.find('/', start);
    const std::string part = path.substr(0, slash);
    if (H5Lexists(loc, part.c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) return true;
    start = slash + 1;
  }
}

// a numbered member (demo_N, traj_N) must be a group: its datasets are looked up inside it
void require_group(hid_t file, const std::string& source, const std::string& path) {
  Handle g(H5Gopen2(file, path.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g.ok()) throw InputError(source, path, "not a group");
}

struct Matrix {
  std::size_t rows{0}, cols{0};
  std::vector<double> v;
  double at(std::size_t r, std::size_t c) const { return v[r * cols + c]; }
};

// why a dataset may not read: a compression filter this HDF5 library lacks (h5py's own lzf is the
// usual one: h5py ships it, libhdf5 does not), else ""
std::string missing_filter(hid_t dataset) {
  Handle dcpl(H5Dget_create_plist(dataset), H5Pclose);
  if (!dcpl.ok()) return "";
  const int n = H5Pget_nfilters(dcpl.get());
  for (int i = 0; i < n; ++i) {
    unsigned flags = 0;
    std::size_t nvalues = 0;
    char name[64] = {0};
    unsigned config = 0;
    const H5Z_filter_t id = H5Pget_filter2(dcpl.get(), static_cast<unsigned>(i), &flags, &nvalues, nullptr, sizeof(name), name, &config);
    if (id >= 0 && H5Zfilter_avail(id) <= 0) {
      const std::string label = id == 32000 ? std::string("lzf") : name[0] ? std::string(name) : std::string();
      return " (compressed with HDF5 filter " + std::to_string(id) + (label.empty() ? "" : " " + quote_input(label)) +
             ", which this HDF5 library does not have; re-save the file with gzip compression or none)";
    }
  }
  return "";
}

Matrix read_matrix(hid_t file, const std::string& source, const std::string& path) {
  if (!exists(file, path)) throw InputError(source, path, "missing dataset");
  Handle d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) throw InputError(source, path, "not a dataset");
  Handle type(H5Dget_type(d.get()), H5Tclose);
  const H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_FLOAT && cls != H5T_INTEGER) throw InputError(source, path, "not a numeric dataset");
  Handle space(H5Dget_space(d.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != 1 && rank != 2) throw InputError(source, path, "must be 1-D or 2-D (rows = steps), got " + std::to_string(rank) + "-D");
  hsize_t dims[2] = {0, 1};
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  Matrix m;
  m.rows = dims[0];
  m.cols = rank == 2 ? dims[1] : 1;
  if (m.rows * m.cols > (std::size_t{1} << 28)) throw InputError(source, path, "too large (more than 2^28 numbers)");
  m.v.resize(m.rows * m.cols);
  if (!m.v.empty() && H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m.v.data()) < 0)
    throw InputError(source, path, "cannot be read as numbers" + missing_filter(d.get()));
  for (std::size_t k = 0; k < m.v.size(); ++k)
    if (!std::isfinite(m.v[k]))
      throw InputError(source, path, "row " + std::to_string(k / m.cols) + " column " + std::to_string(k % m.cols) + ": not a finite number");
  return m;
}

const char* class_name(H5T_class_t c) {
  switch (c) {
    case H5T_INTEGER: return "an HDF5 integer";
    case H5T_FLOAT: return "an HDF5 float";
    case H5T_COMPOUND: return "an HDF5 compound";
    case H5T_ENUM: return "an HDF5 enum";
    case H5T_ARRAY: return "an HDF5 array";
    case H5T_VLEN: return "an HDF5 variable-length sequence";
    case H5T_OPAQUE: return "an HDF5 opaque";
    case H5T_REFERENCE: return "an HDF5 reference";
    case H5T_BITFIELD: return "an HDF5 bitfield";
    case H5T_TIME: return "an HDF5 time";
    default: return "an HDF5 non-string";
  }
}

// A text attribute as its writers store it: h5py writes a Python str as a variable-length UTF-8
// string and numpy bytes (np.bytes_, dtype S) as a fixed-length ASCII string exactly as long as the
// text (NUL-padded, no terminator); either scalar or a one-element array. The memory type copies the
// file's (character set, padding), so HDF5 converts nothing: it has no conversion between character
// sets (a UTF-8 string read as ASCII fails), and a NUL-terminated memory type of the fixed string's
// size would drop the text's last character.
// nullopt when absent; anything else is an InputError naming the attribute.
std::optional<std::string> read_string_attr(hid_t obj, const char* name, const std::string& source, const std::string& where) {
  if (H5Aexists(obj, name) <= 0) return std::nullopt;
  Handle a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) throw InputError(source, where, "cannot be opened");
  Handle type(H5Aget_type(a.get()), H5Tclose);
  const H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_STRING) throw InputError(source, where, std::string("not a string (") + class_name(cls) + " attribute)");
  Handle space(H5Aget_space(a.get()), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n != 1) throw InputError(source, where, std::to_string(n) + " strings, expected one");
  Handle mem(H5Tcopy(type.get()), H5Tclose);
  if (!mem.ok()) throw InputError(source, where, "unreadable string type");
  std::string out;
  if (H5Tis_variable_str(type.get()) > 0) {
    char* s = nullptr;
    if (H5Aread(a.get(), mem.get(), &s) < 0) throw InputError(source, where, "cannot be read as a string");
    if (s) out = s;
    H5free_memory(s);
  } else {
    const std::size_t size = H5Tget_size(type.get());
    if (size == 0 || size > kMaxJsonDocumentBytes) throw InputError(source, where, "string of " + std::to_string(size) + " bytes");
    out.assign(size, '\0');
    if (H5Aread(a.get(), mem.get(), out.data()) < 0) throw InputError(source, where, "cannot be read as a string");
    out.resize(std::strlen(out.c_str()));  // NUL-padded or NUL-terminated
    if (H5Tget_strpad(type.get()) == H5T_STR_SPACEPAD) out.erase(out.find_last_not_of(' ') + 1);
  }
  return out;
}

// the numbered members NAME_0, NAME_1, ... of a group, in numeric order
std::vector<std::pair<long long, std::string>> numbered(hid_t group, const std::string& prefix) {
  std::vector<std::pair<long long, std::string>> out;
  H5G_info_t info;
  if (H5Gget_info(group, &info) < 0) return out;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t n = H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (n <= 0) continue;
    std::string name(static_cast<std::size_t>(n), '\0');
    H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), static_cast<std::size_t>(n) + 1, H5P_DEFAULT);
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.empty() || digits.size() > 15 || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) continue;
    out.emplace_back(std::stoll(digits), name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

Action action_row(const Matrix& a, std::size_t t) {
  Action x = Action::Zero();
  if (a.cols == 4) {  // pd_ee_delta_pos: translation + gripper
    for (int k = 0; k < 3; ++k) x[k] = a.at(t, static_cast<std::size_t>(k));
    x[kGripper] = a.at(t, 3);
  } else {
    for (std::size_t k = 0; k < a.cols; ++k) x[static_cast<Eigen::Index>(k)] = a.at(t, k);
  }
  return x;
}

void check_actions(const Matrix& a, const std::string& source, const std::string& path) {
  if (a.cols != 4 && a.cols != 6 && a.cols != 7)
    throw InputError(source, path, std::to_string(a.cols) + " columns; the audit reads 7 (pose + gripper), 6 (pose) or 4 (pd_ee_delta_pos: translation + gripper)");
}

std::optional<Conventions> maniskill_declaration(const std::string& mode, const std::string& source, std::string* why) {
  Conventions c;
  if (mode == "pd_ee_delta_pose" || mode == "pd_ee_target_delta_pose" || mode == "pd_ee_delta_pos" || mode == "pd_ee_target_delta_pos") {
    c.rotation = RotationRep::kEulerXyz;  // ManiSkill 3 reads the rotation delta as "XYZ" Euler angles
    *why = "control_mode " + mode;
    return c;
  }
  if (mode == "pd_ee_pose") {
    c.action = ActionKind::kNextState;
    c.rotation = RotationRep::kEulerXyz;
    *why = "control_mode " + mode;
    return c;
  }
  if (mode.rfind("pd_joint", 0) == 0 || mode.rfind("pd_base", 0) == 0)
    throw InputError(source, "control_mode", quote_input(mode) + " is joint-space: the audit needs end-effector pose actions (replay the trajectories with -c pd_ee_delta_pose)");
  return std::nullopt;
}

ActionLog read_maniskill(hid_t file, const std::string& path, const std::vector<std::pair<long long, std::string>>& trajs) {
  ActionLog log;
  log.source = path;
  log.layout = "maniskill";
  // the JSON sidecar: control mode
  std::filesystem::path side(path);
  side.replace_extension(".json");
  if (std::filesystem::exists(side)) {
    const std::string text = read_input_file(side.string(), "ManiSkill sidecar", kMaxJsonDocumentBytes);
    const nlohmann::json j = parse_json_input(text, side.string());
    std::string mode;
    if (j.contains("env_info") && j["env_info"].is_object() && j["env_info"].contains("env_kwargs") &&
        j["env_info"]["env_kwargs"].is_object() && j["env_info"]["env_kwargs"].contains("control_mode") &&
        j["env_info"]["env_kwargs"]["control_mode"].is_string())
      mode = j["env_info"]["env_kwargs"]["control_mode"].get<std::string>();
    if (mode.empty()) throw InputError(side.string(), "env_info.env_kwargs.control_mode", "missing");
    std::string why;
    log.declared = maniskill_declaration(mode, side.string(), &why);
    log.declared_from = why;
  }
  int dim = -1;
  for (const auto& [n, name] : trajs) {
    require_group(file, path, name);
    const Matrix a = read_matrix(file, path, name + "/actions");
    check_actions(a, path, name + "/actions");
    if (dim < 0) dim = static_cast<int>(a.cols);
    if (static_cast<int>(a.cols) != dim) throw InputError(path, name + "/actions", "column count differs from the first trajectory's");
    const std::string tcp_path = name + "/obs/extra/tcp_pose";
    if (!exists(file, tcp_path)) {
      if (exists(file, name + "/obs") && !exists(file, name + "/obs/extra"))
        throw InputError(path, tcp_path,
                         "missing: flat state observations do not name the TCP pose; record or replay with obs_mode state_dict");
      throw InputError(path, tcp_path, "missing dataset");
    }
    const Matrix p = read_matrix(file, path, tcp_path);
    if (p.cols != 7) throw InputError(path, tcp_path, std::to_string(p.cols) + " columns, expected 7 (x y z qw qx qy qz)");
    if (p.rows != a.rows && p.rows != a.rows + 1)
      throw InputError(path, tcp_path, std::to_string(p.rows) + " rows for " + std::to_string(a.rows) + " actions (need as many, or one more)");
    std::optional<Matrix> q;
    if (exists(file, name + "/obs/agent/qpos")) {
      q = read_matrix(file, path, name + "/obs/agent/qpos");
      if (q->rows != p.rows || q->cols < 2) throw InputError(path, name + "/obs/agent/qpos", "rows differ from tcp_pose's, or fewer than 2 columns");
    }
    LogEpisode ep;
    for (std::size_t t = 0; t < a.rows; ++t) ep.actions.push_back(action_row(a, t));
    for (std::size_t t = 0; t < p.rows; ++t) {
      TcpPose pose;
      pose.position = Vec3(p.at(t, 0), p.at(t, 1), p.at(t, 2));
      pose.quaternion = Eigen::Vector4d(p.at(t, 3), p.at(t, 4), p.at(t, 5), p.at(t, 6));
      if (!(pose.quaternion.norm() > 1e-9)) throw InputError(path, tcp_path, "row " + std::to_string(t) + ": zero quaternion");
      if (q) pose.fingers = Eigen::Vector2d(q->at(t, q->cols - 2), q->at(t, q->cols - 1));
      ep.poses.push_back(pose);
    }
    log.episodes.push_back(std::move(ep));
  }
  log.has_gripper = dim != 6;
  validate_log(log);
  return log;
}

// robosuite's arm controller as robomimic's env_args records it (env_kwargs.controller_configs):
// before robosuite 1.5 the arm's config itself ({"type": "OSC_POSE", "control_delta": true, ...});
// from 1.5 a composite controller ({"type": "BASIC", "body_parts": {"right": {"type": "OSC_POSE",
// "input_type": "delta", "input_ref_frame": "base", ...}, "torso": ...}}), whose arm part is read.
struct RobosuiteController {
  std::string type;       // the arm's controller, e.g. OSC_POSE
  std::string described;  // how declared_from names it
  std::string absolute;   // non-empty: the key that makes the actions absolute targets
  std::string bad;        // non-empty: why the config declares nothing (no arm part, unknown frame)
};

std::optional<RobosuiteController> robosuite_controller(const nlohmann::json& env, const std::string& source, const std::string& where) {
  const auto member = [&](const nlohmann::json& obj, const char* key, const std::string& at) -> const nlohmann::json* {
    if (!obj.contains(key) || obj[key].is_null()) return nullptr;
    if (!obj[key].is_object()) throw InputError(source, where, at + key + ": not a JSON object");
    return &obj[key];
  };
  const nlohmann::json* kw = member(env, "env_kwargs", "");
  if (!kw) return std::nullopt;
  if (!kw->contains("controller_configs") || (*kw)["controller_configs"].is_null()) return std::nullopt;
  RobosuiteController c;
  const nlohmann::json* cc = &(*kw)["controller_configs"];
  if (cc->is_array()) {  // one config per robot (robosuite's multi-robot environments)
    if (cc->size() != 1) {
      c.described = "robomimic env_args controller_configs";
      c.bad = std::to_string(cc->size()) + " controllers (one per robot); the audit reads one arm";
      return c;
    }
    cc = &(*cc)[0];
  }
  if (!cc->is_object()) throw InputError(source, where, "env_kwargs.controller_configs: not a JSON object");
  const auto text = [&](const nlohmann::json& obj, const char* key, const std::string& at) -> std::string {
    if (!obj.contains(key) || obj[key].is_null()) return {};
    if (!obj[key].is_string()) throw InputError(source, where, at + key + ": not a string");
    return obj[key].get<std::string>();
  };
  const std::string cc_at = "env_kwargs.controller_configs.";
  const nlohmann::json* arm = cc;
  std::string arm_at = cc_at;
  if (const nlohmann::json* parts = member(*cc, "body_parts", cc_at)) {
    const std::string composite = text(*cc, "type", cc_at);
    const char* name = parts->contains("right") ? "right" : parts->contains("left") ? "left" : nullptr;
    c.described = "robomimic env_args controller " + (composite.empty() ? std::string("composite") : composite);
    if (!name) {
      c.bad = "body_parts has no arm part (right or left)";
      return c;
    }
    arm_at = cc_at + "body_parts.";
    arm = member(*parts, name, arm_at);
    arm_at += std::string(name) + ".";
    c.described += ", arm part '" + std::string(name) + "':";
  } else {
    c.described = "robomimic env_args controller";
  }
  c.type = text(*arm, "type", arm_at);
  c.described += " " + (c.type.empty() ? std::string("(no type)") : c.type);
  // robosuite >= 1.5 reads input_type; control_delta is what older versions read (and what robomimic's
  // released configs still write). Either one saying absolute makes the actions absolute targets.
  const std::string input_type = text(*arm, "input_type", arm_at);
  if (!input_type.empty() && input_type != "delta" && input_type != "absolute")
    throw InputError(source, where, arm_at + "input_type: " + quote_input(input_type) + " is neither delta nor absolute");
  if (input_type == "absolute") c.absolute = "input_type absolute";
  if (arm->contains("control_delta") && !(*arm)["control_delta"].is_null()) {
    if (!(*arm)["control_delta"].is_boolean()) throw InputError(source, where, arm_at + "control_delta: not true or false");
    if (!(*arm)["control_delta"].get<bool>() && c.absolute.empty()) c.absolute = "control_delta false";
  }
  const std::string frame = text(*arm, "input_ref_frame", arm_at);
  if (!frame.empty()) {
    c.described += ", input_ref_frame " + frame;
    if (frame != "base" && frame != "world") c.bad = "input_ref_frame " + quote_input(frame) + " is neither base nor world";
  }
  return c;
}

// The declaration a robosuite arm controller makes, given the logged action width: OSC_POSE (7 or 6
// columns) and OSC_POSITION (4: translation + gripper) with delta input declare robosuite's convention
// (delta, base, axis-angle, gripper -1 opens). Otherwise nothing is declared and declared_from says why.
void declare_robosuite(const RobosuiteController& c, int dim, ActionLog* log) {
  const auto refuse = [&](const std::string& why) { log->declared_from = c.described + ": not declared: " + why + "; pass --declared"; };
  if (!c.bad.empty()) return refuse(c.bad);
  if (c.type != "OSC_POSE" && c.type != "OSC_POSITION")
    return refuse("the audit reads robosuite's end-effector controllers OSC_POSE and OSC_POSITION");
  if (!c.absolute.empty())
    return refuse("absolute targets (" + c.absolute +
                  "): robosuite's is a pose in metres and axis-angle in the base or world frame, which neither the grammar's "
                  "absolute target (normalised, from the episode's start) nor next_state (the next logged pose) states exactly");
  const bool fits = c.type == "OSC_POSE" ? (dim == 7 || dim == 6) : dim == 4;
  if (!fits)
    return refuse(std::to_string(dim) + "-column actions, but " + c.type + " takes " + (c.type == "OSC_POSE" ? "7 (or 6 without gripper)" : "4"));
  Conventions conv;
  auto f = Contract::identity().fields();
  f.gripper_inverted = true;  // robosuite: -1 opens, +1 closes
  conv.contract = Contract::make(f);
  log->declared = conv;
  log->declared_from = c.described;
}

ActionLog read_robomimic(hid_t file, const std::string& path) {
  ActionLog log;
  log.source = path;
  log.layout = "robomimic";
  Handle data(H5Gopen2(file, "data", H5P_DEFAULT), H5Gclose);
  if (!data.ok()) throw InputError(path, "data", "not a group");
  const std::string env_where = "data attribute env_args";
  std::optional<RobosuiteController> controller;
  if (auto env = read_string_attr(data.get(), "env_args", path, env_where)) {
    const nlohmann::json j = parse_json_input(*env, path, env_where);
    if (!j.is_object()) throw InputError(path, env_where, "not a JSON object");
    controller = robosuite_controller(j, path, env_where);
  }
  const auto demos = numbered(data.get(), "demo_");
  if (demos.empty()) throw InputError(path, "data", "no demo_N groups");
  int dim = -1;
  for (const auto& [n, name] : demos) {
    const std::string d = "data/" + name;
    require_group(file, path, d);
    const Matrix a = read_matrix(file, path, d + "/actions");
    check_actions(a, path, d + "/actions");
    if (dim < 0) dim = static_cast<int>(a.cols);
    if (static_cast<int>(a.cols) != dim) throw InputError(path, d + "/actions", "column count differs from the first demo's");
    const Matrix pos = read_matrix(file, path, d + "/obs/robot0_eef_pos");
    const Matrix quat = read_matrix(file, path, d + "/obs/robot0_eef_quat");
    if (pos.cols != 3) throw InputError(path, d + "/obs/robot0_eef_pos", "must have 3 columns (x y z)");
    if (quat.cols != 4) throw InputError(path, d + "/obs/robot0_eef_quat", "must have 4 columns (x y z w)");
    if (pos.rows != a.rows || quat.rows != a.rows)
      throw InputError(path, d + "/obs", "robot0_eef_pos/robot0_eef_quat rows differ from the " + std::to_string(a.rows) + " actions");
    std::optional<Matrix> grip;
    if (exists(file, d + "/obs/robot0_gripper_qpos")) {
      grip = read_matrix(file, path, d + "/obs/robot0_gripper_qpos");
      if (grip->rows != a.rows || grip->cols != 2)
        throw InputError(path, d + "/obs/robot0_gripper_qpos",
                         std::to_string(grip->rows) + " x " + std::to_string(grip->cols) + ", expected " + std::to_string(a.rows) +
                             " x 2 (two finger positions, one row per action)");
    }
    const auto pose_at = [&](const Matrix& P, const Matrix& Q, const std::optional<Matrix>& G, std::size_t t, const std::string& where) {
      TcpPose p;
      p.position = Vec3(P.at(t, 0), P.at(t, 1), P.at(t, 2));
      p.quaternion = Eigen::Vector4d(Q.at(t, 3), Q.at(t, 0), Q.at(t, 1), Q.at(t, 2));  // x y z w → w x y z
      if (!(p.quaternion.norm() > 1e-9)) throw InputError(path, where, "row " + std::to_string(t) + ": zero quaternion");
      if (G) p.fingers = Eigen::Vector2d(G->at(t, 0), -G->at(t, 1));
      return p;
    };
    LogEpisode ep;
    for (std::size_t t = 0; t < a.rows; ++t) {
      ep.actions.push_back(action_row(a, t));
      ep.poses.push_back(pose_at(pos, quat, grip, t, d + "/obs/robot0_eef_quat"));
    }
    if (exists(file, d + "/next_obs/robot0_eef_pos") && exists(file, d + "/next_obs/robot0_eef_quat") && a.rows > 0) {
      const Matrix np = read_matrix(file, path, d + "/next_obs/robot0_eef_pos");
      const Matrix nq = read_matrix(file, path, d + "/next_obs/robot0_eef_quat");
      std::optional<Matrix> ng;
      if (grip && exists(file, d + "/next_obs/robot0_gripper_qpos")) ng = read_matrix(file, path, d + "/next_obs/robot0_gripper_qpos");
      if (np.rows == a.rows && nq.rows == a.rows && np.cols == 3 && nq.cols == 4 && (!ng || (ng->rows == a.rows && ng->cols == 2))) {
        TcpPose last = pose_at(np, nq, ng, a.rows - 1, d + "/next_obs/robot0_eef_quat");
        if (grip && !ng) last.fingers.reset();
        if (!grip || ng) ep.poses.push_back(last);
      }
    }
    log.episodes.push_back(std::move(ep));
  }
  log.has_gripper = dim != 6;
  if (controller) declare_robosuite(*controller, dim, &log);
  validate_log(log);
  return log;
}

// ---- writing

class Writer {
 public:
  explicit Writer(const std::string& path) : path_(path), tmp_(path + ".tmp") {
    silence_hdf5();
    require_replaceable_output(path);
    file_ = H5Fcreate(tmp_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file_ < 0) throw std::runtime_error(path + ": cannot create the HDF5 file");
  }
  ~Writer() {
    if (file_ >= 0) H5Fclose(file_);
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  hid_t file() const { return file_; }

  void group(const std::string& name) {
    Handle g(H5Gcreate2(file_, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    if (!g.ok()) throw std::runtime_error(path_ + ": cannot create group " + name);
  }
  void matrix(const std::string& name, std::size_t rows, std::size_t cols, const std::vector<double>& v, bool f32) {
    const hsize_t dims[2] = {rows, cols};
    Handle space(H5Screate_simple(2, dims, nullptr), H5Sclose);
    Handle d(H5Dcreate2(file_, name.c_str(), f32 ? H5T_IEEE_F32LE : H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    if (!d.ok() || (!v.empty() && H5Dwrite(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0))
      throw std::runtime_error(path_ + ": cannot write dataset " + name);
  }
  void string_attr(const std::string& object, const char* name, const std::string& value) {
    Handle obj(H5Oopen(file_, object.c_str(), H5P_DEFAULT), H5Oclose);
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), value.size() + 1);
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    Handle a(H5Acreate2(obj.get(), name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!a.ok() || H5Awrite(a.get(), type.get(), value.c_str()) < 0) throw std::runtime_error(path_ + ": cannot write attribute " + name);
  }
  void commit() {
    H5Fclose(file_);
    file_ = -1;
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) throw std::runtime_error(path_ + ": cannot rename temporary file");
  }

 private:
  std::string path_, tmp_;
  hid_t file_{-1};
};

std::vector<double> action_rows(const LogEpisode& ep, int cols) {
  std::vector<double> v;
  for (const auto& a : ep.actions)
    for (int k = 0; k < cols; ++k) v.push_back(a[k]);
  return v;
}

}  // namespace

ActionLog read_log_hdf5(const std::string& path) {
  silence_hdf5();
  check_input_file(path, "HDF5 log", std::uintmax_t{16} << 30);
  if (H5Fis_hdf5(path.c_str()) <= 0) throw InputError(path, "", "not an HDF5 file");
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) throw InputError(path, "", "cannot open the HDF5 file");
  if (exists(file.get(), "data")) return read_robomimic(file.get(), path);
  Handle root(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose);
  const auto trajs = numbered(root.get(), "traj_");
  if (!trajs.empty()) return read_maniskill(file.get(), path, trajs);
  throw InputError(path, "/", "neither layout: no traj_N groups (ManiSkill) and no data group (robomimic)");
}

ActionLog read_log(const std::string& path) {
  if (ends_with(path, ".h5") || ends_with(path, ".hdf5")) return read_log_hdf5(path);
  return read_log_text(path);
}

void write_log_maniskill(const ActionLog& log, const std::string& path, const std::string& control_mode) {
  {
    Writer w(path);
    const int cols = log.has_gripper ? 7 : 6;
    for (std::size_t e = 0; e < log.episodes.size(); ++e) {
      const auto& ep = log.episodes[e];
      const std::string g = "traj_" + std::to_string(e);
      w.group(g);
      w.matrix(g + "/actions", ep.actions.size(), static_cast<std::size_t>(cols), action_rows(ep, cols), true);
      w.group(g + "/obs");
      w.group(g + "/obs/extra");
      w.group(g + "/obs/agent");
      std::vector<double> tcp, qpos;
      for (const auto& p : ep.poses) {
        for (int k = 0; k < 3; ++k) tcp.push_back(p.position[k]);
        for (int k = 0; k < 4; ++k) tcp.push_back(p.quaternion[k]);
        for (int k = 0; k < 7; ++k) qpos.push_back(0.0);
        qpos.push_back(p.fingers ? (*p.fingers)[0] : 0.0);
        qpos.push_back(p.fingers ? (*p.fingers)[1] : 0.0);
      }
      w.matrix(g + "/obs/extra/tcp_pose", ep.poses.size(), 7, tcp, true);
      if (!ep.poses.empty() && ep.poses.front().fingers) w.matrix(g + "/obs/agent/qpos", ep.poses.size(), 9, qpos, true);
    }
    w.commit();
  }
  nlohmann::json side;
  side["env_info"] = {{"env_id", "ActionShift"}, {"env_kwargs", {{"control_mode", control_mode}, {"obs_mode", "state_dict"}}}};
  side["episodes"] = nlohmann::json::array();
  for (std::size_t e = 0; e < log.episodes.size(); ++e)
    side["episodes"].push_back({{"episode_id", e}, {"control_mode", control_mode}, {"elapsed_steps", log.episodes[e].actions.size()}});
  std::filesystem::path p(path);
  p.replace_extension(".json");
  write_file_atomic(p.string(), side.dump(2) + "\n");
}

void write_log_robomimic(const ActionLog& log, const std::string& path, const std::string& controller) {
  Writer w(path);
  const int cols = log.has_gripper ? 7 : 6;
  w.group("data");
  nlohmann::json env{{"env_name", "ActionShift"}, {"type", 1}, {"env_kwargs", {{"controller_configs", {{"type", controller}}}}}};
  w.string_attr("data", "env_args", env.dump());
  for (std::size_t e = 0; e < log.episodes.size(); ++e) {
    const auto& ep = log.episodes[e];
    const std::string g = "data/demo_" + std::to_string(e);
    const std::size_t T = ep.actions.size();
    w.group(g);
    w.matrix(g + "/actions", T, static_cast<std::size_t>(cols), action_rows(ep, cols), false);
    const bool fingers = !ep.poses.empty() && ep.poses.front().fingers.has_value();
    for (const char* which : {"obs", "next_obs"}) {
      const std::size_t off = std::string(which) == "obs" ? 0 : 1;
      if (off == 1 && ep.poses.size() < T + 1) continue;
      const std::size_t rows = std::min(T, ep.poses.size() - off);
      w.group(g + "/" + which);
      std::vector<double> pos, quat, grip;
      for (std::size_t t = 0; t < rows; ++t) {
        const auto& p = ep.poses[t + off];
        for (int k = 0; k < 3; ++k) pos.push_back(p.position[k]);
        quat.insert(quat.end(), {p.quaternion[1], p.quaternion[2], p.quaternion[3], p.quaternion[0]});
        if (fingers) grip.insert(grip.end(), {(*p.fingers)[0], -(*p.fingers)[1]});
      }
      w.matrix(g + "/" + which + "/robot0_eef_pos", rows, 3, pos, false);
      w.matrix(g + "/" + which + "/robot0_eef_quat", rows, 4, quat, false);
      if (fingers) w.matrix(g + "/" + which + "/robot0_gripper_qpos", rows, 2, grip, false);
    }
  }
  w.commit();
}

}  // namespace actionshift::selftest
