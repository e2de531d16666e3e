#pragma once
/// \file Audit a log (docs/audit.md): identify the action contract of recorded robot data, without
/// probing, with calibrated abstention. Given the commanded actions and the measured TCP poses of a
/// log, the declared convention (a contract of the grammar plus the conventions of the extension
/// below) and a response model (a task's calibration, or fitted from the log), answer PASS (the log
/// agrees with the declaration), MISMATCH (which contract of the grammar explains the log, field by
/// field in words, with its posterior) or INCONCLUSIVE (the log does not excite the fields that would
/// decide: which ones, and what motion would).
///
/// Identification fits, for every (target, frame, lag) hypothesis, each output channel's response on
/// all six raw channels at once, with uncertainty from the log itself (a jackknife and cross-validation
/// over its episodes); a field is committed only when every hypothesis the log cannot exclude agrees on
/// it, and lags and scales outside the grammar are named so. Depends on core only (no simulator).
///
/// The extension beyond the paper's grammar (it changes no contract, split or hash): the rotation
/// representation of the rotation deltas (axis-angle vs two Euler orders), the gripper range ([−1, 1]
/// vs [0, 1]) and "the action is the next state" (the logged action equals the next logged pose).

#include "actionshift/adapt/response.hpp"
#include "actionshift/core/contract.hpp"
#include "actionshift/core/types.hpp"
#include "actionshift/selftest/selftest.hpp"
#include "actionshift/selftest/verdict.hpp"

#include <nlohmann/json_fwd.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::selftest {

/// How the three rotation numbers of an action describe a rotation increment.
enum class RotationRep {
  kAxisAngle,  ///< a rotation vector (axis × angle): the canonical semantics
  kEulerXyz,   ///< intrinsic X-Y-Z Euler angles, R = Rx(rx)·Ry(ry)·Rz(rz) (pytorch3d/ManiSkill 3 "XYZ", scipy "XYZ")
  kEulerZyx,   ///< intrinsic Z-Y-X Euler angles, R = Rz(rz)·Ry(ry)·Rx(rx) (= static x-y-z: transforms3d "sxyz", scipy "xyz")
};
const char* to_string(RotationRep r);      ///< "axis_angle", "euler_xyz", "euler_zyx"
std::string describe(RotationRep r);       ///< in words, e.g. "XYZ Euler angles (R = Rx·Ry·Rz)"
std::optional<RotationRep> parse_rotation_rep(std::string_view s);

/// The range of the gripper channel: [−1, 1] (canonical) or [0, 1] (g01 = (g + 1) / 2).
enum class GripperRange { kSymmetric, kUnit };
const char* to_string(GripperRange g);     ///< "[-1, 1]" or "[0, 1]"
std::optional<GripperRange> parse_gripper_range(std::string_view s);  ///< "-1..1"/"[-1, 1]"/"symmetric", "0..1"/"[0, 1]"/"unit"

/// What the logged action is.
enum class ActionKind {
  kCommand,       ///< a command of the contract grammar (delta or absolute target in normalised units)
  kNextState,     ///< the next logged pose ("action is the next state": absolute target = pose at t + 1)
  kCurrentState,  ///< the current logged pose (the off-by-one of "ee_pose at t instead of t + 1")
};
const char* to_string(ActionKind a);       ///< "command", "next_state", "current_state"
std::optional<ActionKind> parse_action_kind(std::string_view s);

/// A declared (or identified) convention: a contract of the grammar plus the extension's conventions.
struct Conventions {
  Contract contract;                                ///< permutation, sign, scale, target, frame, lag, gripper polarity
  RotationRep rotation{RotationRep::kAxisAngle};
  GripperRange gripper_range{GripperRange::kSymmetric};
  ActionKind action{ActionKind::kCommand};

  /// {"contract": {...}, "rotation": "...", "gripper_range": "...", "action": "..."}.
  nlohmann::json to_json_value() const;
  /// Accepts either a bare contract object (the seven contract keys; the extension at its defaults) or
  /// the object above (every key optional; a "recorded" object, the provenance `actionshift record
  /// --truth` writes, is ignored). Throws InputError(source, field, reason).
  static Conventions from_json_value(const nlohmann::json& j, const std::string& source);
};

/// One episode of a log: `poses[t]` is measured before `actions[t]` is executed; `poses` has as many
/// entries as `actions` (the last action's response is unknown and unused) or one more.
struct LogEpisode {
  std::vector<Action> actions;  ///< raw actions as logged (gripper 0 when the log has none)
  std::vector<TcpPose> poses;   ///< TCP poses in the robot base frame (fingers optional, per pose)
};

/// A log: episodes plus what the file said about itself.
struct ActionLog {
  std::string source{"log"};         ///< file name (messages)
  std::vector<LogEpisode> episodes;
  bool has_gripper{true};            ///< the gripper channel was logged
  std::string layout{"columns"};     ///< "csv", "jsonl", "maniskill", "robomimic", "arrays"
  /// A declaration the file carries (ManiSkill's sidecar control_mode), if the reader understood one.
  std::optional<Conventions> declared;
  /// where `declared` came from, e.g. "control_mode pd_ee_delta_pose"; set while `declared` is empty, why the
  /// file's own declaration was not taken (e.g. a robosuite controller with absolute targets)
  std::string declared_from;

  std::size_t transitions() const;   ///< steps with a measured response
  /// The first `max_transitions` transitions (whole episodes, the last one cut).
  ActionLog head(std::size_t max_transitions) const;
};

/// Checks every number is finite, every quaternion non-zero and at least one transition exists;
/// throws InputError(source, "episode E step T: <field>", reason).
void validate_log(const ActionLog& log);

/// Audit settings.
struct AuditOptions {
  Conventions declared;                         ///< default: identity, axis-angle, [−1, 1], command
  /// Response per unit canonical command (a task's calibration); unset: fitted from the log itself,
  /// and the scale field is then reported relative to the fitted gain, not checked.
  std::optional<adapt::ResponseModel> model;
  /// The one-sided level of every test (a hypothesis excluded, a coefficient standing out of its
  /// jackknife uncertainty), in (0, 1]. The defaults of this struct's thresholds are the configuration
  /// the audit benchmark chose on its tuning set (docs/results/audit.md).
  double confidence_floor{0.99};
  double misspec_ratio{25.0};      ///< abstain when the best contract fits worse than this × the calibrated noise variance
  double min_rotation_spread{0.2}; ///< [rad] the TCP turn the report asks for when the frame is not resolved
  /// How far (a factor) a log's response gain may lie from the calibrated one: the calibration's random
  /// walks and a policy's sustained, saturated or contact-bound motion run at different gains (on the
  /// benchmark's tuning logs 0.2x to 2x). A channel's scale is claimed as the band of the log's gain /
  /// calibrated gain within this factor, widened by two jackknife standard errors.
  double gain_tolerance{5.0};
  /// A raw channel commanded with an RMS below this (normalised units) resolves no output channel: in a
  /// closed-loop log a policy's small corrections answer disturbances, which biases their apparent
  /// response (measured on the simulator: a sign read backwards at RMS 0.04).
  double min_excitation{0.1};
  /// A read raw channel must explain at least this share of its output channel's motion variance: in a
  /// closed loop a channel whose motion is mostly contacts and drift, with the policy's corrections
  /// answering them, shows a command-response slope of either sign.
  double min_explained{0.2};
  /// Rows whose residual under the best hypothesis exceeds this many robust standard deviations (and
  /// action cells far outside the log's range) are left out: a few corrupted rows decide nothing.
  double outlier_z{6.0};
  /// A rival (target, frame, lag) hypothesis is excluded only if it predicts the log's motion worse by at
  /// least this log ratio of prediction errors (0.05: 5 %), significantly: a hypothesis that is merely
  /// detectably worse (a tool frame that hardly turns, a slow response) is not excluded.
  double min_margin{0.05};
  /// The grammar wires one raw channel to each output channel: a channel that a second raw channel
  /// moves at more than this fraction of the read channel's amplitude is coupled (contacts, a closed
  /// loop's reactions, an arm pulling against the table), and its wiring is not committed.
  double max_coupling{0.5};
};
/// One line naming the field and rule, or "" if valid.
std::string validate(const AuditOptions& o);

/// One audited field.
struct AuditField {
  std::string name;            ///< permutation, sign, scale, target, frame, lag, gripper_inverted, gripper_range, rotation, action
  std::string declared;        ///< declared value (Python style for the grammar fields)
  std::string identified;      ///< identified value ("?" on the channels that are not resolved)
  double confidence{0.0};      ///< posterior mass of the identified value (the weakest channel for per-channel fields)
  bool checked{true};          ///< false: the log cannot tell (reason says why)
  bool resolved{false};        ///< every channel reaches the floor
  std::vector<int> unresolved_channels;  ///< output channels below the floor (per-channel fields)
  std::string diff;            ///< the difference in words, over resolved channels only ("" if none)
  std::string reason;          ///< unchecked: why; unresolved: what motion would decide
};

/// The audit's answer.
struct AuditResult {
  Status status{Status::kInconclusive};
  std::string reason;
  Conventions declared;
  Conventions identified;              ///< the best hypothesis (only its resolved fields are claimed)
  std::vector<AuditField> fields;
  double fit_ratio{0.0};               ///< mean squared residual of the MAP / calibrated noise variance
  double noise_inflation{1.0};         ///< the residual-based noise scale the posterior used / calibrated
  bool model_fitted{false};            ///< the response model was fitted from the log
  std::array<double, kPoseDim> alpha{};      ///< response gain used per output channel
  std::array<double, kPoseDim> effective_gain{};  ///< α·sign·scale of the MAP per output channel
  /// Per output channel, the scales consistent with the log: [lo, hi] of the log's gain / calibrated gain
  /// widened by the gain tolerance and two standard errors (calibrated model only).
  std::array<std::array<double, 2>, kPoseDim> scale_band{};
  std::array<double, kPoseDim> excitation{};      ///< RMS raw command per raw channel
  // what the verdict commits to (for programs that score audits): -1 / 0 / false / nullopt = not committed
  std::array<int, kPoseDim> committed_raw{};      ///< raw channel read per output channel
  std::array<int, kPoseDim> committed_sign{};     ///< ±1 per output channel
  std::array<bool, kPoseDim> scale_committed{};   ///< the scale_band is a claim (calibrated model only)
  std::optional<std::string> committed_target, committed_frame;
  std::optional<int> committed_lag;               ///< may lie outside the grammar's lags (named so)
  std::optional<bool> committed_gripper_inverted;
  std::size_t outlier_rows{0};         ///< rows left out of the fits (corrupted cells, outlying responses)
  double evidence_t{0};                ///< paired t of "the actions explain the motion" against ignoring them
  double t_critical{0};                ///< the threshold every test of this audit used
  int plausible_modes{0};              ///< (target, frame, lag) hypotheses the log cannot exclude
  std::size_t episodes{0};
  std::size_t transitions{0};
  std::string source;

  /// Exit code of `actionshift audit`: 0 PASS, 1 MISMATCH, 3 INCONCLUSIVE (2 is bad input there).
  int exit_code() const;
  const AuditField* field(std::string_view name) const;
};

/// Audits `log` against `options.declared`. Throws InputError for an invalid log and
/// std::invalid_argument for invalid options.
AuditResult audit(const ActionLog& log, const AuditOptions& options);

/// Human report.
std::string to_text(const AuditResult& r);
/// Machine report: one JSON object, indent 2, sorted keys.
std::string to_json(const AuditResult& r);
nlohmann::json to_json_value(const AuditResult& r);

// ---- file formats without HDF5 (docs/audit.md, "Formats")

/// CSV with a header row of named columns: episode (optional), action_0..action_5 and optionally
/// action_6 (gripper), tcp_x tcp_y tcp_z, tcp_qw tcp_qx tcp_qy tcp_qz, finger_0 finger_1 (optional);
/// other columns are ignored. Throws InputError(path, "line N: column C", reason).
ActionLog read_log_csv(const std::string& path);
/// JSON lines: one object per step: {"episode": E, "action": [7 or 6], "tcp_pos": [3],
/// "tcp_quat": [w, x, y, z], "fingers": [2]} ("episode", "fingers" optional).
ActionLog read_log_jsonl(const std::string& path);
/// By extension: .csv, .jsonl/.ndjson; other extensions are an InputError (HDF5: audit_hdf5.hpp).
ActionLog read_log_text(const std::string& path);
/// Writers of the same formats (atomic: a temporary file beside `path`, then renamed).
void write_log_csv(const ActionLog& log, const std::string& path);
void write_log_jsonl(const ActionLog& log, const std::string& path);

// ---- a synthetic log (tests, docs): no simulator

struct SyntheticLogOptions {
  int episodes{4};
  int steps{50};                 ///< actions per episode (poses: steps + 1)
  double amplitude{0.6};         ///< |command| bound of the smooth random excitation
  double smoothness{0.8};        ///< AR(1) coefficient of the excitation
  double yaw_spread{0.8};        ///< [rad] random start yaw per episode (excites the frame)
  bool fingers{true};            ///< log finger positions
  std::uint64_t seed{1};
};
/// A log from the canonical excitation encoded through `truth` (raw = what the robot is sent), the
/// robot decoding with `truth` (live TCP rotation for the tool frame) and moving by α ⊙ canonical +
/// σ·N(0, 1), its rotation increments applied in `truth.rotation`; the gripper range and polarity
/// of `truth` decide the logged gripper numbers, fingers follow 0.015 + 0.025·g with noise.
/// truth.action other than kCommand logs poses as actions.
ActionLog synthetic_log(const Conventions& truth, const adapt::ResponseModel& model, const SyntheticLogOptions& o);

}  // namespace actionshift::selftest
