// Audit logs: the CSV and JSON-lines formats (docs/audit.md, "Formats") and the synthetic log.
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/input_file.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/rng.hpp"
#include "actionshift/core/weight_file.hpp"
#include "actionshift/selftest/audit.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <sstream>

namespace actionshift::selftest {

namespace {

constexpr std::uintmax_t kMaxLogBytes = kMaxInputFileBytes;

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string trim(std::string_view s) {
  std::size_t a = 0, b = s.size();
  while (a < b && (s[a] == ' ' || s[a] == '\t' || s[a] == '\r')) ++a;
  while (b > a && (s[b - 1] == ' ' || s[b - 1] == '\t' || s[b - 1] == '\r')) --b;
  return std::string(s.substr(a, b - a));
}

std::vector<std::string> split_csv(std::string_view line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= line.size(); ++i)
    if (i == line.size() || line[i] == ',') {
      out.push_back(trim(line.substr(start, i - start)));
      start = i + 1;
    }
  return out;
}

double parse_number(const std::string& cell, const std::string& source, const std::string& field) {
  if (cell.empty()) throw InputError(source, field, "empty cell (a number is required)");
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  if (end != cell.c_str() + cell.size()) throw InputError(source, field, "not a number (" + quote_input(cell, '\'', 40) + ")");
  if (!std::isfinite(v) || errno == ERANGE) throw InputError(source, field, "not a finite number (" + quote_input(cell, '\'', 40) + ")");
  return v;
}

long long parse_integer(const std::string& cell, const std::string& source, const std::string& field) {
  const double v = parse_number(cell, source, field);
  if (v != std::floor(v) || std::abs(v) > 9e15) throw InputError(source, field, "not an integer (" + quote_input(cell, '\'', 40) + ")");
  return static_cast<long long>(v);
}

// rows grouped into episodes by consecutive episode ids; an id met again later is an error
struct EpisodeBuilder {
  ActionLog& log;
  std::map<long long, bool> seen;
  long long current{0};
  bool open{false};
  bool final_pose{false};  // the open episode ended with a pose-only row

  void row(long long episode, const std::optional<Action>& action, const TcpPose& pose, const std::string& where) {
    if (!open || episode != current) {
      if (seen.count(episode)) throw InputError(log.source, where + ": episode", "episode " + std::to_string(episode) + " appears again after another episode");
      seen[episode] = true;
      log.episodes.emplace_back();
      current = episode;
      open = true;
      final_pose = false;
    } else if (final_pose) {
      throw InputError(log.source, where, "a row after the episode's final pose-only row (empty action)");
    }
    auto& ep = log.episodes.back();
    ep.poses.push_back(pose);
    if (action) ep.actions.push_back(*action);
    else final_pose = true;
  }
};

const std::vector<std::string> kActionCols{"action_0", "action_1", "action_2", "action_3", "action_4", "action_5", "action_6"};
const std::vector<std::string> kPoseCols{"tcp_x", "tcp_y", "tcp_z", "tcp_qw", "tcp_qx", "tcp_qy", "tcp_qz"};

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

bool all_fingers(const ActionLog& log) {
  for (const auto& e : log.episodes)
    for (const auto& p : e.poses)
      if (!p.fingers) return false;
  return true;
}

}  // namespace

ActionLog read_log_csv(const std::string& path) {
  const std::string text = read_input_file(path, "log", kMaxLogBytes);
  ActionLog log;
  log.source = path;
  log.layout = "csv";
  std::istringstream in(text);
  std::string line;
  std::size_t line_no = 0;
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++line_no;
    if (!trim(line).empty()) {
      header = split_csv(line);
      break;
    }
  }
  if (header.empty()) throw InputError(path, "", "empty file (a header row of column names is required)");
  std::map<std::string, std::size_t> col;
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (col.count(header[i])) throw InputError(path, "line " + std::to_string(line_no) + ": column " + printable_input(header[i], 40), "appears twice");
    col[header[i]] = i;
  }
  for (std::size_t k = 0; k < 6; ++k)
    if (!col.count(kActionCols[k])) throw InputError(path, "header", "missing column " + kActionCols[k]);
  for (const auto& c : kPoseCols)
    if (!col.count(c)) throw InputError(path, "header", "missing column " + c);
  log.has_gripper = col.count("action_6") > 0;
  const bool fingers = col.count("finger_0") && col.count("finger_1");
  if (!fingers && (col.count("finger_0") || col.count("finger_1")))
    throw InputError(path, "header", "finger_0 and finger_1 come together (got only one)");
  const bool has_episode = col.count("episode") > 0;
  EpisodeBuilder b{log, {}, 0, false, false};
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const auto cells = split_csv(line);
    const std::string where = "line " + std::to_string(line_no);
    if (cells.size() != header.size())
      throw InputError(path, where, std::to_string(cells.size()) + " cells, the header has " + std::to_string(header.size()));
    const auto cell = [&](const std::string& name) -> const std::string& { return cells[col.at(name)]; };
    const auto field = [&](const std::string& name) { return where + ": column " + name; };
    long long episode = has_episode ? parse_integer(cell("episode"), path, field("episode")) : 0;
    bool empty_action = true;
    for (std::size_t k = 0; k < (log.has_gripper ? 7u : 6u); ++k) empty_action = empty_action && cell(kActionCols[k]).empty();
    std::optional<Action> action;
    if (!empty_action) {
      Action a = Action::Zero();
      for (std::size_t k = 0; k < (log.has_gripper ? 7u : 6u); ++k)
        a[static_cast<Eigen::Index>(k)] = parse_number(cell(kActionCols[k]), path, field(kActionCols[k]));
      action = a;
    }
    TcpPose p;
    for (int k = 0; k < 3; ++k) p.position[k] = parse_number(cell(kPoseCols[static_cast<std::size_t>(k)]), path, field(kPoseCols[static_cast<std::size_t>(k)]));
    for (int k = 0; k < 4; ++k)
      p.quaternion[k] = parse_number(cell(kPoseCols[static_cast<std::size_t>(3 + k)]), path, field(kPoseCols[static_cast<std::size_t>(3 + k)]));
    if (!(p.quaternion.norm() > 1e-9)) throw InputError(path, field("tcp_qw..tcp_qz"), "zero quaternion");
    if (fingers) p.fingers = Eigen::Vector2d(parse_number(cell("finger_0"), path, field("finger_0")), parse_number(cell("finger_1"), path, field("finger_1")));
    b.row(episode, action, p, where);
  }
  validate_log(log);
  return log;
}

ActionLog read_log_jsonl(const std::string& path) {
  const std::string text = read_input_file(path, "log", kMaxLogBytes);
  ActionLog log;
  log.source = path;
  log.layout = "jsonl";
  EpisodeBuilder b{log, {}, 0, false, false};
  std::istringstream in(text);
  std::string line;
  std::size_t line_no = 0;
  int action_dim = -1;
  int with_fingers = -1;
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const std::string where = "line " + std::to_string(line_no);
    const nlohmann::json j = parse_json_input(line, path, where);
    if (!j.is_object()) throw InputError(path, where, "not a JSON object");
    const auto numbers = [&](const char* key, std::size_t n_min, std::size_t n_max) {
      const std::string f = where + ": " + key;
      if (!j.contains(key)) throw InputError(path, f, "missing");
      const auto& v = j[key];
      if (!v.is_array() || v.size() < n_min || v.size() > n_max)
        throw InputError(path, f, "must be an array of " + std::to_string(n_min) + (n_min == n_max ? "" : " or " + std::to_string(n_max)) + " numbers");
      std::vector<double> out;
      for (std::size_t k = 0; k < v.size(); ++k) {
        if (!v[k].is_number()) throw InputError(path, f + "[" + std::to_string(k) + "]", "not a number");
        const double x = v[k].get<double>();
        if (!std::isfinite(x)) throw InputError(path, f + "[" + std::to_string(k) + "]", "not a finite number");
        out.push_back(x);
      }
      return out;
    };
    long long episode = 0;
    if (j.contains("episode")) {
      if (!j["episode"].is_number_integer()) throw InputError(path, where + ": episode", "must be an integer");
      episode = j["episode"].get<long long>();
    }
    std::optional<Action> action;
    if (j.contains("action") && !j["action"].is_null()) {
      const auto a = numbers("action", 6, 7);
      if (action_dim < 0) action_dim = static_cast<int>(a.size());
      if (static_cast<int>(a.size()) != action_dim)
        throw InputError(path, where + ": action", std::to_string(a.size()) + " numbers, earlier lines have " + std::to_string(action_dim));
      Action x = Action::Zero();
      for (std::size_t k = 0; k < a.size(); ++k) x[static_cast<Eigen::Index>(k)] = a[k];
      action = x;
    } else if (!j.contains("action")) {
      throw InputError(path, where + ": action", "missing (null marks an episode's final pose)");
    }
    TcpPose p;
    const auto pos = numbers("tcp_pos", 3, 3);
    const auto q = numbers("tcp_quat", 4, 4);
    p.position = Vec3(pos[0], pos[1], pos[2]);
    p.quaternion = Eigen::Vector4d(q[0], q[1], q[2], q[3]);
    if (!(p.quaternion.norm() > 1e-9)) throw InputError(path, where + ": tcp_quat", "zero quaternion");
    const bool f = j.contains("fingers") && !j["fingers"].is_null();
    if (with_fingers < 0) with_fingers = f;
    if (f != (with_fingers == 1)) throw InputError(path, where + ": fingers", "present on some lines only");
    if (f) {
      const auto fv = numbers("fingers", 2, 2);
      p.fingers = Eigen::Vector2d(fv[0], fv[1]);
    }
    b.row(episode, action, p, where);
  }
  log.has_gripper = action_dim != 6;
  validate_log(log);
  return log;
}

ActionLog read_log_text(const std::string& path) {
  if (ends_with(path, ".csv")) return read_log_csv(path);
  if (ends_with(path, ".jsonl") || ends_with(path, ".ndjson")) return read_log_jsonl(path);
  throw InputError(path, "", "unknown log format: the name must end in .csv, .jsonl, .ndjson (or .h5/.hdf5 for the HDF5 layouts)");
}

void write_log_csv(const ActionLog& log, const std::string& path) {
  const bool fingers = all_fingers(log);
  std::string out = "episode,step";
  for (std::size_t k = 0; k < (log.has_gripper ? 7u : 6u); ++k) out += "," + kActionCols[k];
  for (const auto& c : kPoseCols) out += "," + c;
  if (fingers) out += ",finger_0,finger_1";
  out += "\n";
  for (std::size_t e = 0; e < log.episodes.size(); ++e) {
    const auto& ep = log.episodes[e];
    for (std::size_t t = 0; t < ep.poses.size(); ++t) {
      out += std::to_string(e) + "," + std::to_string(t);
      for (int k = 0; k < (log.has_gripper ? 7 : 6); ++k) out += "," + (t < ep.actions.size() ? num(ep.actions[t][k]) : std::string());
      const auto& p = ep.poses[t];
      for (int k = 0; k < 3; ++k) out += "," + num(p.position[k]);
      for (int k = 0; k < 4; ++k) out += "," + num(p.quaternion[k]);
      if (fingers) out += "," + num((*p.fingers)[0]) + "," + num((*p.fingers)[1]);
      out += "\n";
    }
  }
  write_file_atomic(path, out);
}

void write_log_jsonl(const ActionLog& log, const std::string& path) {
  const bool fingers = all_fingers(log);
  std::string out;
  for (std::size_t e = 0; e < log.episodes.size(); ++e) {
    const auto& ep = log.episodes[e];
    for (std::size_t t = 0; t < ep.poses.size(); ++t) {
      nlohmann::json j;
      j["episode"] = e;
      j["step"] = t;
      if (t < ep.actions.size()) {
        std::vector<double> a;
        for (int k = 0; k < (log.has_gripper ? 7 : 6); ++k) a.push_back(ep.actions[t][k]);
        j["action"] = a;
      } else {
        j["action"] = nullptr;
      }
      const auto& p = ep.poses[t];
      j["tcp_pos"] = {p.position[0], p.position[1], p.position[2]};
      j["tcp_quat"] = {p.quaternion[0], p.quaternion[1], p.quaternion[2], p.quaternion[3]};
      if (fingers) j["fingers"] = {(*p.fingers)[0], (*p.fingers)[1]};
      out += j.dump() + "\n";
    }
  }
  write_file_atomic(path, out);
}

// ---- synthetic log

ActionLog synthetic_log(const Conventions& truth, const adapt::ResponseModel& model, const SyntheticLogOptions& o) {
  model.validate();
  if (o.episodes < 1 || o.steps < 1) throw std::invalid_argument("synthetic_log: episodes and steps must be >= 1");
  ActionLog log;
  log.source = "synthetic";
  log.layout = "arrays";
  Rng rng(o.seed);
  Decoder dec(truth.contract);
  const double lo = truth.gripper_range == GripperRange::kUnit ? 0.0 : -1.0;
  for (int e = 0; e < o.episodes; ++e) {
    dec.reset(0);
    LogEpisode ep;
    TcpPose pose;
    pose.position = Vec3(0.4 + 0.05 * rng.normal(), 0.05 * rng.normal(), 0.3);
    const double yaw = rng.uniform(-o.yaw_spread, o.yaw_spread);
    Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX()));
    double finger = 0.04;
    Pose6 x = Pose6::Zero();
    double grip = 1.0;  // raw gripper in the log's range: hi or lo, toggled now and then
    const int toggle = 6 + static_cast<int>(rng.uniform_int(6));
    std::vector<TcpPose> poses;
    std::vector<Action> commands;
    for (int t = 0; t <= o.steps; ++t) {
      pose.quaternion = Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
      if (o.fingers) pose.fingers = Eigen::Vector2d(finger + 2e-4 * rng.normal(), finger + 2e-4 * rng.normal());
      poses.push_back(pose);
      if (t == o.steps) break;
      for (int c = 0; c < kPoseDim; ++c)
        x[c] = std::clamp(o.smoothness * x[c] + std::sqrt(1 - o.smoothness * o.smoothness) * o.amplitude * rng.normal(), -o.amplitude, o.amplitude);
      if (t % toggle == toggle - 1) grip = grip > 0.5 ? lo : 1.0;
      Action raw;
      raw.head<kPoseDim>() = x;
      raw[kGripper] = grip;
      commands.push_back(raw);
      // the robot: gripper range, the contract's decode (live rotation), the response
      Action in = raw;
      if (truth.gripper_range == GripperRange::kUnit) in[kGripper] = 2 * raw[kGripper] - 1;
      const Mat3 R = q.toRotationMatrix();
      const Action c = dec.step(in, R);
      for (int k = 0; k < 3; ++k)
        pose.position[k] += model.alpha[static_cast<std::size_t>(k)] * c[k] + model.sigma[static_cast<std::size_t>(k)] * rng.normal();
      Vec3 v;
      for (int k = 0; k < 3; ++k)
        v[k] = model.alpha[static_cast<std::size_t>(k + 3)] * c[k + 3] + model.sigma[static_cast<std::size_t>(k + 3)] * rng.normal();
      Mat3 dR;
      switch (truth.rotation) {
        case RotationRep::kEulerXyz:
          dR = (Eigen::AngleAxisd(v[0], Vec3::UnitX()) * Eigen::AngleAxisd(v[1], Vec3::UnitY()) * Eigen::AngleAxisd(v[2], Vec3::UnitZ())).toRotationMatrix();
          break;
        case RotationRep::kEulerZyx:
          dR = (Eigen::AngleAxisd(v[2], Vec3::UnitZ()) * Eigen::AngleAxisd(v[1], Vec3::UnitY()) * Eigen::AngleAxisd(v[0], Vec3::UnitX())).toRotationMatrix();
          break;
        default:
          dR = v.norm() > 0 ? Eigen::AngleAxisd(v.norm(), v / v.norm()).toRotationMatrix() : Mat3::Identity();
      }
      q = Eigen::Quaterniond(dR * q.toRotationMatrix()).normalized();
      const double target = 0.015 + 0.025 * std::clamp(c[kGripper], -1.0, 1.0);
      finger += 0.5 * (target - finger);
    }
    ep.poses = poses;
    if (truth.action == ActionKind::kCommand) {
      ep.actions = commands;
    } else {
      for (int t = 0; t < o.steps; ++t) {
        const TcpPose& p = poses[static_cast<std::size_t>(truth.action == ActionKind::kNextState ? t + 1 : t)];
        Action a = commands[static_cast<std::size_t>(t)];
        a.head<3>() = p.position;
        const Eigen::Quaterniond pq(p.quaternion[0], p.quaternion[1], p.quaternion[2], p.quaternion[3]);
        const Eigen::AngleAxisd aa(pq);
        a.segment<3>(3) = aa.angle() * aa.axis();
        ep.actions.push_back(a);
      }
    }
    log.episodes.push_back(std::move(ep));
  }
  return log;
}

}  // namespace actionshift::selftest
