// CLI11 registration of run, plan, summarize, gate1, gate check | promote, compare and calibrate
// (cmd_run.cpp, cmd_eval.cpp, cmd_compare.cpp implement them), and the options that name one job
// (run, render, record)
#include "cli_common.hpp"
#include "cmd_eval.hpp"
#include "cmd_run.hpp"
#include "commands.hpp"

#include "actionshift/sim/env.hpp"

#include <cstdint>
#include <iostream>

namespace actionshift::cli {

// the options that name one job: `run` and `render` share them, so a render reaches the run's job id
void add_job_options(CliContext& ctx, CLI::App* cmd, CliJobOptions& j, bool required) {
  auto* task = cmd->add_option("--task", j.request.task, ctx.task_list)->check(kNotEmpty);
  auto* split = cmd->add_option("--split", j.request.split, "Split manifest: a built-in name (seen, reference_seen, ...) or a file")
                    ->check(kNotEmpty);
  auto* method = cmd->add_option("--method", j.request.method.name,
                                 "Adapter method (docs/adapters.md): " + ctx.method_list +
                                     ". A bare name runs the paper's method; a variant is NAME{VARIANT} or NAME{KEY=VALUE,...} "
                                     "(quote it for the shell), e.g. 'entropy_probes{calibrated}'")
                     ->check(kNotEmpty);
  if (required) {
    task->required();
    split->required();
    method->required();
  }
  cmd->add_option("--params", j.method_params, "Method parameters as a JSON object (defaults: docs/adapters.md)")
      ->capture_default_str();
  auto* seed = cmd->add_option("--seed", j.request.seed, "Experimental seed")->check(kSeed)->capture_default_str();
  cmd->add_option("--seed-file", j.seed_file,
                  "Read the experimental seed from FILE (one integer) instead of --seed: an evaluator's undisclosed seed "
                  "stays off the command line, which any process on the machine can read (docs/formats.md §1)")
      ->excludes(seed);
  cmd->add_option("--episodes", j.request.episodes,
                  "Episodes, dealt in blocks over the split's contracts: each contract once per block, in a seeded order, "
                  "every contract of a block from the same initial state")
      ->capture_default_str();
  cmd->add_option("--backbone", j.request.backbone, "Frozen policy: expert, mlp, external:<command>, ...")
      ->capture_default_str();
  cmd->add_option("--pool", j.request.pool, "Declared pool for pool-belief methods: reference9, full or a file");
  cmd->add_option("--rotation-mode", j.request.rotation_mode, "Tool-frame rotation: live (TCP) or identity")
      ->capture_default_str();
  cmd->add_option("--profile", j.request.profile,
                  "Simulator fidelity profile: maniskill (one-step IK, PD drives with inertia, as ManiSkill) or\n"
                  "ideal (converged IK, first-order servo); part of the job id (docs/sim.md)")->check(kProfile)
      ->capture_default_str();
  cmd->add_option("--obs-noise", j.request.obs_noise,
                  "Observation (sensor) noise, OFF by default: sigma of Gaussian noise on the observed TCP pose, in\n"
                  "metres per position coordinate and radians per rotation-vector component (0..0.1), drawn per\n"
                  "episode; seen by policy and adapter alike; part of the job id when non-zero (docs/sim.md 6.1)")
      ->capture_default_str();
  cmd->add_option("--horizon", j.request.horizon,
                  "Control steps per episode (0: the task's, 50; peg_insertion_side 100); part of the job id when\n"
                  "not 0 (the reference evaluates its Diffusion Policy at 100)")
      ->check(CLI::Range(0, sim::kMaxHorizon))
      ->capture_default_str();
  cmd->add_option("--calibration", j.calibration,
                  "Response calibration file for a method that needs one, instead of the task's built-in one (e.g.\n"
                  "`calibrate --obs-noise S --out FILE`); its hash is the job's calibration_sha256");
  add_robot_options(cmd, j.robot, /*makes_jobs=*/true);
  cmd->add_option("--method-rung", j.method_rung,
                  "--method external:<command> only: the rung it claims, pool, grammar or none (what the runner hands it;\n"
                  "docs/methods.md)")
      ->capture_default_str();
  cmd->add_option("--method-version", j.method_version, "--method external:<command> only: its declared version (in the job id)")
      ->capture_default_str();
  cmd->add_option("--method-files", j.method_files,
                  "--method external:<command> only: its script, weights, configuration (their content enters the job id)");
  cmd->add_option("--policy-files", j.policy_files,
                  "Files of an external:<command> backbone (script, weights, config): their content hash enters the\n"
                  "job id, so editing the policy makes a new job instead of reusing old results");
}

void register_eval_commands(CLI::App& app, CliContext& ctx) {
  // ---- run | plan | summarize | gate1 | gate check | calibrate (eval layer)
  auto& run_o = ctx.make<cli::RunCliOptions>();
  auto& run_job_index = ctx.make<std::int64_t>(-1);
  auto* run = app.add_subcommand(
      "run",
      "Run an evaluation job: episodes of a backbone under each contract of a split, through a method's\n"
      "adapter, written as one JSONL record per episode to <out>/<job id>.jsonl (+ .summary.json). The job\n"
      "id is the SHA-256 of everything that determines the episodes; a finished job is a no-op and a killed\n"
      "one resumes. Ctrl-C or SIGTERM stops it after the episodes already finished (exit 130; a second\n"
      "signal ends it at once). Either --task/--split/--method/--seed, or --plan FILE [--job-index I].");
  add_job_options(ctx, run, run_o.job, /*required=*/false);
  run->add_option("--plan", run_o.run.plan_file, "Run the jobs of a plan file (actionshift plan) instead")->check(kNotEmpty);
  auto* job_index = run->add_option("--job-index", run_job_index, "With --plan: only this job (a Slurm array task id)")
      ->check(CLI::Validator(
          [](std::string& v) { return !v.empty() && v[0] == '-' ? "must be a job index >= 0 (got " + v + ")" : std::string(); }, ""));
  run->add_option("--out", run_o.run.out_dir, "Results directory")->capture_default_str();
  run->add_option("--threads", run_o.run.threads, "Worker threads (0: all cores; at most 1024)")->check(CLI::Range(0, 1024))->capture_default_str();
  run->add_flag("--fsync", run_o.run.fsync, "fsync after every record");
  run->add_option("--progress", run_o.run.progress, "auto, bar, lines or off")->capture_default_str();
  run->add_option("--step-timeout", run_o.run.step_timeout_s,
                  "Seconds an external:<command> backbone may take to read one request and to reply to it\n"
                  "(a process that overruns, floods replies or dies ends the job with an error)")
      ->check(CLI::Range(0.001, 86400.0) & kNotNan)
      ->capture_default_str();
  run->add_option("--sandbox", run_o.run.sandbox,
                  "auto, on or off: external:<command> backbones and methods run in new user, mount and PID\n"
                  "namespaces where they see no process of the runner's and find --out, --plan and --seed-file\n"
                  "empty (auto: when this machine allows it, else with a warning; on: or fail)")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  run->callback([&ctx, &run_o, &run_job_index, job_index] {
    ctx.action = [&run_o, &run_job_index, job_index] {
      if (job_index->count() > 0 && run_o.run.plan_file.empty()) {  // was ignored: the single job ran
        std::cerr << "actionshift: error: --job-index: only applies with --plan (see --help)\n";
        return static_cast<int>(cli::kBadInput);
      }
      if (run_job_index >= 0) run_o.run.job_index = run_job_index;
      if (run_o.run.plan_file.empty() &&
          (run_o.job.request.task.empty() || run_o.job.request.split.empty() || run_o.job.request.method.name.empty())) {
        std::cerr << "actionshift: error: run needs --task, --split and --method, or --plan (see --help)\n";
        return static_cast<int>(cli::kBadInput);
      }
      return cli::run_run(run_o);
    };
  });

  auto& plan_o = ctx.make<cli::PlanOptions>();
  auto* plan = app.add_subcommand(
      "plan", "Expand an experiment (configs/experiments/<name>.yaml) into its job list. --slurm also writes, beside\n"
              "the plan, <name>.sbatch (one array task per job: `actionshift run --plan ... --job-index`), <name>.merge.sbatch\n"
              "(summarize, and gate1 when the plan has oracle and no_adapt) and <name>.submit.sh, which submits the arrays in\n"
              "chunks under the cluster's MaxArraySize and the merge job with --dependency=afterok. Every path in them is\n"
              "absolute, so `bash <name>.submit.sh` works from any directory.");
  plan->add_option("--experiment", plan_o.experiment_file, "Experiment YAML")->required()->check(kNotEmpty);
  plan->add_option("--out", plan_o.out_dir, "Results directory of the jobs")->capture_default_str();
  plan->add_option("--plan", plan_o.plan_file, "Plan file (default <out>/<experiment>.plan.json)");
  plan->add_flag("--slurm", plan_o.slurm, "Also write a Slurm array script");
  plan->add_option("--slurm-script", plan_o.slurm_file, "Script path (default <out>/<experiment>.sbatch)");
  plan->add_option("--executable", plan_o.executable,
                   "The actionshift binary the array tasks call (default: this binary; a bare name is looked up on PATH;\n"
                   "written as an absolute path)");
  plan->add_option("--cpus-per-task", plan_o.cpus_per_task, "Slurm --cpus-per-task (also the tasks' --threads)")->capture_default_str();
  plan->add_option("--time", plan_o.time_limit, "Slurm --time per array task: M, M:S, H:M:S, D-H, D-H:M, D-H:M:S or UNLIMITED")
      ->capture_default_str();
  plan->add_option("--mem", plan_o.mem, "Slurm --mem per array task, e.g. 4G (default: the cluster's)");
  plan->add_option("--partition", plan_o.partition, "Slurm --partition");
  plan->add_option("--max-parallel", plan_o.max_parallel, "Array throttle (%N)");
  plan->add_option("--max-array-size", plan_o.max_array_size,
                   "Tasks per array (default: MaxArraySize from `scontrol show config`, else Slurm's default 1001)");
  auto& plan_robot = ctx.make<cli::RobotOptions>();
  add_robot_options(plan, plan_robot, /*makes_jobs=*/true);
  auto& plan_policy_files = ctx.make<std::vector<std::string>>();
  plan->add_option("--policy-files", plan_policy_files,
                   "Files of an external:<command> backbone (script, weights); their content hash enters every job id");
  plan->callback([&] { ctx.action = [&] { return cli::run_plan_cli(plan_o, plan_robot, plan_policy_files); }; });

  auto& sum_o = ctx.make<cli::SummarizeOptions>();
  auto* summarize = app.add_subcommand("summarize", "Merge every <id>.jsonl in a directory into per-cell tables (Markdown or JSON)");
  summarize->add_option("dir", sum_o.results_dir, "Results directory")->required()->check(kNotEmpty);
  summarize->add_flag("--json", sum_o.json, "Print JSON instead of Markdown");
  summarize->add_option("--out", sum_o.out_file, "Also write the JSON summary to this file");
  summarize->callback([&] { ctx.action = [&] { return cli::run_summarize(sum_o); }; });

  auto& g1_o = ctx.make<cli::Gate1Options>();
  auto* gate1 = app.add_subcommand(
      "gate1", "Gate 1 (privileged ceiling vs no adaptation): per task and split, oracle and no_adapt success with\n"
               "Wilson intervals and their paired bootstrap difference; writes a verdict file; exit 1 if a gated cell fails.");
  gate1->add_option("--results", g1_o.results_dir, "Results directory")->required();
  gate1->add_flag("--json", g1_o.json, "Print JSON");
  gate1->add_option("--verdict", g1_o.verdict_file, "Verdict file (default <results>/gate1.verdict.json)");
  gate1->add_option("--samples", g1_o.samples, "Bootstrap resamples")->check(CLI::Range(1, 1000000))->capture_default_str();
  gate1->add_option("--bootstrap-seed", g1_o.bootstrap_seed, "Bootstrap seed")->check(kSeed)->capture_default_str();
  gate1->callback([&] { ctx.action = [&] { return cli::run_gate1(g1_o); }; });

  auto* gate = app.add_subcommand("gate", "Compare gate verdicts with committed expectations (CI)");
  gate->require_subcommand(1);
  auto& gc_o = ctx.make<cli::GateCheckOptions>();
  auto* gate_check = gate->add_subcommand(
      "check", "Recompute verdicts from --results (or read --actual) and exit 1 if an expected pass regressed");
  gate_check->add_option("--expected", gc_o.expected_file, "Committed verdict file")->required();
  gate_check->add_option("--results", gc_o.results_dir, "Results directory to recompute from");
  gate_check->add_option("--actual", gc_o.actual_file, "A verdict file to compare instead");
  gate_check->callback([&] { ctx.action = [&] { return cli::run_gate_check(gc_o); }; });
  auto& gp_o = ctx.make<cli::GatePromoteOptions>();
  auto* gate_promote = gate->add_subcommand(
      "promote", "Promotion gate (docs/reference.md, section Gates): a candidate method vs its matched baseline per task and split: >= 5 points\n"
                 "(paired 95 % bootstrap interval above 0) or a success-vs-probe-cost Pareto point, without a safety\n"
                 "regression; a one-seed result under 0.3 is never promoted; < 3 matched seeds: extend_seeds.");
  gate_promote->add_option("--candidate", gp_o.candidate, "Candidate method")->required();
  gate_promote->add_option("--baseline", gp_o.baseline, "Matched baseline method")->required();
  gate_promote->add_option("--results", gp_o.results_dir, "Results directory")->required();
  gate_promote->add_flag("--json", gp_o.json, "Print the verdict file");
  gate_promote->add_option("--verdict", gp_o.verdict_file, "Verdict file (default <results>/promotion.<c>.vs.<b>.json)");
  gate_promote->callback([&] { ctx.action = [&] { return cli::run_gate_promote(gp_o); }; });

  auto& cmp_o = ctx.make<cli::CompareOptions>();
  auto* compare = app.add_subcommand(
      "compare",
      "Everything a results page needs, as one JSON document (docs/formats.md, Comparison): per cell (task, split,\n"
      "method label, backbone) success with its Wilson 95 % interval, per-seed rates, probe steps and displacement,\n"
      "safety-flag rates and the paper's number; per --pair and (task, split, backbone) holding both labels the\n"
      "paired bootstrap difference (10000 resamples, seed 20260718), per-seed differences, the paper's difference\n"
      "with its significance, whether the signs agree, and the promotion verdict with the rule that decided.\n"
      "Cells whose episodes do not pair exactly are an error. Method labels are opaque and may hold '{', ',' and\n"
      "'=' (e.g. entropy_probes{calibrated}); only a label without a {...} suffix gets the paper's numbers.");
  compare->add_option("results", cmp_o.results_dirs, "Results directories (their records are merged)")->required();
  compare->add_option("--pair", cmp_o.pairs,
                      "A comparison 'CANDIDATE vs BASELINE' (one argument, quoted; the separator is ' vs ' with its\n"
                      "spaces, so labels may hold any other character); repeatable");
  compare->add_option("--pairs-from", cmp_o.pairs_file,
                      "A file of pairs: one 'CANDIDATE vs BASELINE' per line; blank lines and # comments ignored");
  compare->add_option("--paper", cmp_o.paper_file,
                      "Paper-numbers file (default: configs/paper/numbers.json as compiled into this build)");
  compare->add_option("--out", cmp_o.out_file, "Write the JSON here (default: stdout)");
  compare->add_flag("--common-episodes", cmp_o.common_episodes,
                    "Pair only the episodes both cells of a pair hold (a 50-episode job with the first 50 of a\n"
                    "200-episode one) instead of refusing cells whose episode sets differ; each comparison says in\n"
                    "'unpaired' how many it left out. Check those counts: an unfinished job is left out silently otherwise");
  compare->add_flag("--across-backbones", cmp_o.across_backbones,
                    "Backbone as a random effect: for each same-backbone pair and each (task, split) that two or\n"
                    "more backbones hold, add to 'across_backbones' the difference per backbone (cluster bootstrap\n"
                    "over seed and block, a block being the episodes that share an initial state), pooled over the\n"
                    "backbones (hierarchical bootstrap: backbones, then seeds, then blocks) and a verdict:\n"
                    "holds_on_every_backbone, holds_on_average, depends_on_backbone or not_shown");
  compare->callback([&] { ctx.action = [&] { return cli::run_compare(cmp_o); }; });

  auto& cal_o = ctx.make<cli::CalibrateOptions>();
  auto* calibrate = app.add_subcommand(
      "calibrate", "Measure each pose channel's response gain, noise and R^2 on the unwrapped environment with\n"
                   "random actions (the likelihood of the belief adapters); prints the table, --out writes the JSON.");
  calibrate->add_option("--task", cal_o.task, "Task")->required();
  calibrate->add_option("--profile", cal_o.profile, "Simulator fidelity profile: maniskill or ideal")->check(kProfile)->capture_default_str();
  calibrate->add_option("--protocol", cal_o.protocol,
                        "maniskill_walk (the public reference implementation's, as it runs in ManiSkill: 8 random\n"
                        "walks of 64 steps, truncated and reset at the task's 50-step horizon as ManiSkill's vector\n"
                        "wrapper does, 63 samples each), reference_walk (the same walks without the reset) or\n"
                        "episodes (task episodes with resets, capped at the horizon)")
      ->capture_default_str();
  calibrate->add_option("--episodes", cal_o.calibration.episodes, "Random walks (maniskill_walk, reference_walk) or episodes; 1 to 100000")->check(CLI::Range(1, 100000))->capture_default_str();
  calibrate->add_option("--steps", cal_o.calibration.steps, "Steps per walk or episode (at least 2: a response needs two poses)")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000000));
  calibrate->add_option("--ik", cal_o.ik, "Ablation: override the profile's IK: single_step or converged");
  calibrate->add_option("--drive", cal_o.drive, "Ablation: override the arm drive: implicit_pd or velocity_servo");
  calibrate->add_option("--solver-iterations", cal_o.solver_iterations,
                        "Ablation: Bullet solver iterations per step, 1..1000 (default: the profile's, 15)");
  calibrate->add_option("--joint-limits", cal_o.joint_limits, "Ablation: arm joint limit constraints on or off");
  calibrate->add_option("--seed", cal_o.calibration.seed, "Seed")->check(kSeed)->capture_default_str();
  calibrate->add_option("--obs-noise", cal_o.obs_noise,
                        "Measure under observation noise of this sigma (as run --obs-noise; off by default); the\n"
                        "calibration's profile label gets [obs_noise=S]")
      ->capture_default_str();
  calibrate->add_option("--out", cal_o.out, "Write the calibration JSON here (e.g. configs/calibration/<profile>/<task>.json)");
  calibrate->add_flag("--json", cal_o.json, "Print the calibration JSON");
  add_robot_options(calibrate, cal_o.robot);
  calibrate->add_flag("--gripper-channel", cal_o.calibration.gripper_channel,
                      "Also fit the finger channel (gripper action vs mean finger-position change per step), which\n"
                      "grammar_belief uses with {\"gripper_channel\":true}; adds the optional \"gripper\" key");
  calibrate->callback([&] { ctx.action = [&] { return cli::run_calibrate(cal_o); }; });
}

}  // namespace actionshift::cli
