"""The paper's published numbers that more than one results page sets beside ours. Standard library only.
TABLE5[(task, split, method)] = (success, mean probe steps): the paper's Table 5 (tournament) and, for
oracle and no_adapt, its Table 2 (Gate 1); frozen PPO on ManiSkill, 3 seeds x 200 episodes."""

TABLE5 = {}
def put(task, split, vals):
    for m, v in vals.items():
        TABLE5[(task, split, m)] = v
put("pick_cube", "reference_seen", {"oracle": (1.000, 0), "no_adapt": (0.000, 0), "exact_belief": (0.929, 0.0), "entropy_probes": (0.987, 6.0),
    "fixed_probes": (0.928, 6.0), "random_probes": (0.925, 6.0), "dualabi": (0.983, 2.78)})
put("pick_cube", "reference_unseen_composition", {"oracle": (0.995, 0), "no_adapt": (0.000, 0), "exact_belief": (0.958, 0.0), "entropy_probes": (0.975, 6.0),
    "fixed_probes": (0.970, 6.0), "random_probes": (0.980, 6.0), "dualabi": (0.983, 3.14)})
put("pick_cube", "reference_long_lag", {"oracle": (0.027, 0), "no_adapt": (0.005, 0), "exact_belief": (0.022, 0.0), "entropy_probes": (0.025, 6.0),
    "fixed_probes": (0.037, 6.0), "dualabi": (0.020, 1.61)})
put("push_cube", "reference_seen", {"oracle": (1.000, 0), "no_adapt": (0.003, 0), "exact_belief": (0.983, 0.0), "entropy_probes": (1.000, 6.0),
    "fixed_probes": (0.982, 6.0), "random_probes": (0.942, 6.0), "dualabi": (1.000, 2.60)})
put("push_cube", "reference_unseen_composition", {"oracle": (1.000, 0), "no_adapt": (0.000, 0), "exact_belief": (0.995, 0.0), "entropy_probes": (0.987, 6.0),
    "fixed_probes": (0.980, 6.0), "random_probes": (0.995, 6.0), "dualabi": (0.993, 3.03)})
put("push_cube", "reference_long_lag", {"oracle": (0.153, 0), "no_adapt": (0.000, 0), "exact_belief": (0.117, 0.0), "entropy_probes": (0.100, 6.0),
    "fixed_probes": (0.215, 6.0), "dualabi": (0.110, 1.28)})
put("pull_cube", "reference_seen", {"oracle": (1.000, 0), "no_adapt": (0.000, 0), "exact_belief": (0.952, 0.0), "entropy_probes": (0.975, 6.0),
    "fixed_probes": (0.970, 6.0), "random_probes": (0.943, 6.0), "dualabi": (0.968, 2.91)})
put("pull_cube", "reference_unseen_composition", {"oracle": (0.998, 0), "no_adapt": (0.000, 0), "exact_belief": (0.935, 0.0), "entropy_probes": (0.982, 6.0),
    "fixed_probes": (0.927, 6.0), "random_probes": (0.997, 6.0), "dualabi": (0.977, 2.50)})
put("pull_cube", "reference_long_lag", {"oracle": (0.322, 0), "no_adapt": (0.000, 0), "exact_belief": (0.287, 0.0), "entropy_probes": (0.325, 6.0),
    "fixed_probes": (0.260, 6.0)})
put("stack_cube", "reference_seen", {"oracle": (0.965, 0), "no_adapt": (0.000, 0), "exact_belief": (0.945, 0), "entropy_probes": (0.910, 6.0),
    "fixed_probes": (0.945, 6.0), "random_probes": (0.925, 6.0), "dualabi": (0.945, 2.94)})
put("stack_cube", "reference_unseen_composition", {"oracle": (0.960, 0), "no_adapt": (0.000, 0), "exact_belief": (0.960, 0), "entropy_probes": (0.940, 6.0),
    "fixed_probes": (0.915, 6.0), "random_probes": (0.930, 6.0), "dualabi": (0.960, 3.48)})
put("stack_cube", "reference_long_lag", {"oracle": (0.000, 0), "no_adapt": (0.000, 0)})
