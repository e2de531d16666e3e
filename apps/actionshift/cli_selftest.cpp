// CLI11 registration of selftest, audit and record (cmd_selftest.cpp, cmd_audit.cpp implement them)
#include "cli_common.hpp"
#include "cmd_audit.hpp"
#include "cmd_selftest.hpp"

#include <iostream>

namespace actionshift::cli {

void register_selftest_commands(CLI::App& app, CliContext& ctx) {
  // ---- selftest (plug-and-verify; its own exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input)
  auto& st_o = ctx.make<cli::SelftestOptions>();
  auto* st = app.add_subcommand(
      "selftest",
      "Plug-and-verify self-test: probe with bounded pulses, identify the action wiring over a declared pool\n"
      "and answer PASS, MISMATCH (with the diff in words) or INCONCLUSIVE (abstain). Contract arguments: a\n"
      "library name, MANIFEST:INDEX (e.g. reference_seen:0), a file with contract JSON, or inline JSON.\n"
      "Exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input. See docs/selftest.md.");
  st->footer("Exit codes: 0 PASS, 1 MISMATCH, 2 INCONCLUSIVE, 3 bad input or usage.");
  st->add_option("--task", st_o.task,
                 ctx.task_list + ": the environment probed with\n--sim, the report's task otherwise")
      ->capture_default_str();
  auto* st_demo = st->add_option("--demo", st_o.demo,
                                 "Synthetic demo wiring: identity, swapped-axes, sign-flip, miswired, scaled, reversed, lagged, unmodeled");
  st->add_option("--hidden-contract", st_o.hidden_contract, "The robot's true wiring (default: the expected contract)")
      ->excludes(st_demo);
  st->add_option("--expected", st_o.expected, "The wiring the policy assumes")->capture_default_str();
  st->add_flag("--sim", st_o.sim, "Probe the Bullet environment of --task instead of the synthetic stand-in");
  st->add_option("--profile", st_o.profile, "--sim: simulator fidelity profile: maniskill or ideal (docs/sim.md)")->check(kProfile)
      ->capture_default_str();
  st->add_option("--calibration", st_o.calibration, "--sim: response calibration JSON (default: the task's built-in one)");
  st->add_option("--frame-rotation", st_o.frame_rotation, "--sim: live (TCP orientation) or identity")->capture_default_str();
  st->add_option("--pool", st_o.pools,
                 "Declared pool: library, a manifest name or file (repeatable; default library, with --sim library + reference9)");
  st->add_option("--strategy", st_o.strategy, "Probe strategy: fixed or entropy")->capture_default_str();
  st->add_option("--budget", st_o.budget, "Probe steps (default 6, also with --sim: docs/selftest.md)");
  st->add_option("--amplitude", st_o.amplitude, "Probe bound per pose channel, in (0, 1] (default 0.5)");
  st->add_option("--confidence-floor", st_o.confidence_floor, "Per-field confidence needed to resolve a field")
      ->capture_default_str();
  st->add_option("--misspec-ratio", st_o.misspec_ratio,
                 "Abstain when the best fit exceeds this many times the noise (default 4; with --sim the task's value\n"
                 "calibrated on the simulator's own residuals, configs/selftest/sim_misspec.json)");
  st->add_option("--calibrate-misspec", st_o.calibrate_misspec,
                 "--sim: measure the misspecification threshold on the simulator (every pool member as the hidden\n"
                 "wiring, 8 seeds from --seed; max fit ratio of the correctly identified runs x 1.5) and write the\n"
                 "task's entry of this JSON file (configs/selftest/sim_misspec.json, embedded at build time)");
  st->add_option("--seed", st_o.seed, "Seed (synthetic noise; sim episode)")->check(kSeed)->capture_default_str();
  st->add_flag("--json", st_o.json, "Print one JSON object instead of the text report");
  add_robot_options(st, st_o.robot);
  st->callback([&] { ctx.action = [&] { return cli::run_selftest(st_o); }; });

  // ---- audit | record (issue 37: a recorded log's action contract, docs/audit.md)
  auto& audit_o = ctx.make<cli::AuditCliOptions>();
  auto* audit = app.add_subcommand(
      "audit",
      "Audit a log: identify the action contract of recorded data (commanded actions + measured TCP poses) without\n"
      "probing. PASS, MISMATCH (the contract of the grammar that explains the log, in words) or INCONCLUSIVE\n"
      "(which fields the log does not excite, and what motion would decide). See docs/audit.md.");
  audit->footer("Exit codes: 0 PASS, 1 MISMATCH, 2 bad input or usage, 3 INCONCLUSIVE.");
  audit->add_option("log", audit_o.log, "The log: .csv, .jsonl, or .h5/.hdf5 (ManiSkill trajectory or robomimic layout)")
      ->required()->check(kNotEmpty);
  audit->add_option("--declared", audit_o.declared,
                    "The declared convention: a contract (library name, MANIFEST:INDEX, file or inline JSON) or a conventions\n"
                    "JSON {\"contract\": ..., \"rotation\": ..., \"gripper_range\": ..., \"action\": ...} (default: what the file\n"
                    "declares, e.g. ManiSkill's control_mode, else identity)");
  audit->add_option("--rotation", audit_o.rotation, "Declared rotation representation: axis_angle, euler_xyz or euler_zyx");
  audit->add_option("--gripper-range", audit_o.gripper_range, "Declared gripper range: -1..1 or 0..1");
  audit->add_option("--action-kind", audit_o.action_kind, "Declared meaning of the action: command, next_state or current_state");
  auto* audit_cal = audit->add_option("--calibration", audit_o.calibration, "Response calibration JSON (per-channel gain and noise)");
  audit->add_option("--task", audit_o.task, "Use this task's built-in calibration (pick_cube, ...)")->excludes(audit_cal);
  audit->add_option("--profile", audit_o.profile, "With --task: the simulator profile of the calibration")->check(kProfile)
      ->capture_default_str();
  audit->add_option("--confidence-floor", audit_o.audit.confidence_floor,
                    "Confidence a field needs to be committed: the one-sided level of the tests over the log's episodes\n"
                    "(a hypothesis excluded, a coefficient standing out of its jackknife uncertainty)")->capture_default_str();
  audit->add_option("--min-explained", audit_o.audit.min_explained,
                    "Share of an output channel's motion variance its read raw channel must explain to be committed")
      ->capture_default_str();
  audit->add_option("--max-coupling", audit_o.audit.max_coupling,
                    "An output channel that a second raw channel moves at more than this fraction of the read channel's\n"
                    "amplitude is coupled, and its wiring is not committed")->capture_default_str();
  audit->add_option("--min-margin", audit_o.audit.min_margin,
                    "A rival hypothesis is excluded only if it predicts the motion worse by at least this log ratio")
      ->capture_default_str();
  audit->add_option("--outlier-z", audit_o.audit.outlier_z,
                    "Rows whose residual exceeds this many robust standard deviations are left out")->capture_default_str();
  audit->add_option("--misspec-ratio", audit_o.audit.misspec_ratio, "With a calibration: abstain when the best hypothesis fits worse than this x the calibrated noise variance")
      ->capture_default_str();
  audit->add_option("--gain-tolerance", audit_o.audit.gain_tolerance,
                    "Factor by which a log's response gain may differ from the calibrated one: a channel's scale is\n"
                    "claimed only as the band of the log's gain within this factor (and two standard errors)")->capture_default_str();
  audit->add_option("--max-steps", audit_o.max_steps, "Audit only the first N transitions");
  audit->add_flag("--json", audit_o.json, "Print one JSON object instead of the text report");
  audit->callback([&] { ctx.action = [&] { return cli::run_audit(audit_o); }; });

  auto& record_o = ctx.make<cli::RecordOptions>();
  auto* record = app.add_subcommand(
      "record", "Write a log (actions, TCP poses, fingers) of one contract of a job from the simulator, for `audit` (docs/audit.md)");
  add_job_options(ctx, record, record_o.job, /*required=*/true);
  record->add_option("--contract", record_o.contract, "The split's contract to record (its episodes of the job)")->capture_default_str();
  record->add_option("--steps", record_o.steps, "Stop once this many transitions are logged");
  record->add_option("--out", record_o.out, "The log: .csv, .jsonl or .h5")->required()->check(kNotEmpty);
  record->add_option("--layout", record_o.layout, "For .h5: maniskill or robomimic")->capture_default_str();
  record->add_option("--truth", record_o.truth, "Write the recorded contract (conventions JSON) to this file");
  record->callback([&] { ctx.action = [&] { return cli::run_record(record_o); }; });
}

}  // namespace actionshift::cli
