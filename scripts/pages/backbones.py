"""Naming and ordering shared by the pages that lay out several PPO backbones of one task (the committed
file and its independently trained replicas): docs/results/backbone_variance.md and the learned-backbone
section of docs/results/ladder.md."""
import os

from . import fmt

# the ladder's order (the paper's Fig. 4, bottom to top)
RUNGS = ["no_adapt", "osi", "probe_osi", "recurrent_osi", "grammar_belief", "fixed_probes", "random_probes", "entropy_probes", "exact_belief", "dualabi", "oracle"]


def training_seed(backbone):
    """The committed `ppo` file is the replica of training seed 20260718; a replica names its seed."""
    if backbone == "ppo":
        return "20260718 (committed)"
    stem = os.path.basename(backbone)
    return stem.split(".seed")[1].split(".")[0] if ".seed" in stem else backbone


def rung_key(label):
    """The ladder's order of a method label, a variant after its base."""
    base = label.split("{")[0]
    return (RUNGS.index(base) if base in RUNGS else len(RUNGS), label)


# the paper's findings (its methods, its probe rule) among the across-backbones pairs (scripts/backbone_variance.pairs)
PAPER_PAIRS = ["oracle vs no_adapt", "entropy_probes vs no_adapt", "entropy_probes vs fixed_probes",
               "dualabi vs entropy_probes", "oracle vs entropy_probes", "grammar_belief{probe=hold} vs no_adapt",
               "entropy_probes vs grammar_belief{probe=hold}", "grammar_belief{probe=hold} vs grammar_belief",
               "osi vs no_adapt", "grammar_belief vs osi"]
VERDICT_TEXT = {"holds_on_every_backbone": "holds on every backbone", "holds_on_average": "holds on average",
                "depends_on_backbone": "depends on the backbone", "not_shown": "not shown"}


def diff_text(d):
    """A difference [interval] of compare, bold where the interval excludes 0."""
    mark = "**" if d["direction"] != "none" else ""
    return f"{mark}{fmt.signed(d['estimate'])} [{fmt.signed(d['lower'])}, {fmt.signed(d['upper'])}]{mark}"
