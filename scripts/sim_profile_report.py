#!/usr/bin/env python3
"""Per-control-step cost breakdown of the tournament's mix (scripts/sim_profile).

Reads callgrind_annotate's inclusive listing of `actionshift run` over profile_mix.yaml, the JSONL
records of that run (control steps, episodes) and `actionshift bench env --raw-bullet --json` lines;
writes the figures to a JSON file and regenerates the table between the sim-profile markers of the
benchmarks page. Inclusive counts of nested parts are subtracted from their parents, so every
instruction is counted once.
"""
import argparse
import datetime
import json
import re
import statistics
import sys

BEGIN, END = "<!-- sim-profile:begin -->", "<!-- sim-profile:end -->"

# function-name patterns (demangled, as callgrind_annotate prints them), first match per pattern summed
PATTERNS = {
    "episode": r"eval::\(anonymous namespace\)::Context::run\(",
    "hidden_step": r"sim::HiddenContractEnv::step\(std::span",
    "hidden_reset": r"sim::HiddenContractEnv::reset\(",
    "env_step": r"sim::Env::step\(std::span",
    "step_control": r"detail::PhysicsWorld::step_control\(\)",
    "bullet": r"btDiscreteDynamicsWorld::stepSimulation\(",
    "drive": r"detail::PhysicsWorld::apply_implicit_pd\(",
    "contact_forces": r"detail::PhysicsWorld::compute_contact_forces\(\)",
    "ik": r"sim::single_step_ik\(",
    "snapshot": r"sim::Env::snapshot\(\) const",
    "evaluate": r"sim::evaluate_task\(",
    "policy": r"policy::.*::act\(",
    "adapter_encode": r"adapt::.*::encode\(Eigen::Matrix<double, 7, 1, 0, 7, 1> const&, Eigen::Matrix<double, 3, 3",
    "adapter_observe": r"adapt::.*::observe\(Eigen::Matrix<double, 7, 1, 0, 7, 1> const&, Eigen::Matrix<double, 6, 1",
    "adapter_fingers": r"adapt::.*::observe_fingers\(",
    "adapter_begin": r"adapt::.*::begin_episode\(",
    "adapter_make": r"adapt::make_adapter\(",
    "tcp_glue": r"adapt::tcp_(rotation|response)\(",
    "record": r"eval::(validate_record\(|stamp_record\(|ResultStore::append\()",
    "store_open": r"eval::ResultStore::open\(",
    "total": r"^PROGRAM TOTALS",
}


def parse_inclusive(path):
    """{function name: inclusive Ir} from callgrind_annotate --inclusive=yes output."""
    out = {}
    total = None
    line_re = re.compile(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(?:\S+?:)?(.*?)(?:\s+\[[^\]]*\])?\s*$")
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if "PROGRAM TOTALS" in line:
                total = int(line.split()[0].replace(",", ""))
                continue
            m = line_re.match(line)
            if not m:
                continue
            ir = int(m.group(1).replace(",", ""))
            name = m.group(2)
            # callgrind_annotate prefixes "file:"; the file part never contains "(" while names do
            if ":" in name.split("(")[0] and not name.startswith(("std::", "actionshift::", "bt", "Eigen::")):
                name = name.split(":", 1)[1]
            out[name] = max(out.get(name, 0), ir)
    return out, total


def pick(funcs, pattern, many=False):
    rx = re.compile(pattern)
    hits = [(n, ir) for n, ir in funcs.items() if rx.search(n)]
    if not hits:
        return 0, []
    if many:
        return sum(ir for _, ir in hits), [n for n, _ in hits]
    n, ir = max(hits, key=lambda x: x[1])
    return ir, [n]


def fmt_ir(x):
    return f"{x / 1e6:.2f} M" if x >= 1e6 else f"{x / 1e3:.1f} k"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--inclusive", required=True)
    ap.add_argument("--exclusive")
    ap.add_argument("--records", required=True)
    ap.add_argument("--raw", required=True)
    ap.add_argument("--json", required=True)
    ap.add_argument("--page", required=True)
    ap.add_argument("--commit", required=True)
    ap.add_argument("--nproc", type=int, default=0)
    ap.add_argument("--niced", type=int, default=0)
    ap.add_argument("--raw-steps", type=int, default=0)
    ap.add_argument("--baseline", help="an earlier sim_profile.json whose callgrind figures are shown as 'before'")
    ap.add_argument("--baseline-label", default="before")
    ap.add_argument("--baseline-raw", help="`bench env --raw-bullet --json` lines of the baseline binary, run interleaved with --raw")
    a = ap.parse_args()

    funcs, total = parse_inclusive(a.inclusive)
    prof = None
    if funcs:
        many = {"policy", "adapter_encode", "adapter_observe", "adapter_fingers", "adapter_begin", "tcp_glue", "record"}
        ir, names = {}, {}
        for k, p in PATTERNS.items():
            if k == "total":
                continue
            ir[k], names[k] = pick(funcs, p, many=k in many)
        steps = episodes = 0
        with open(a.records, encoding="utf-8") as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    steps += int(r["steps"])
                    episodes += 1
        if steps == 0:
            sys.exit("sim_profile_report: no control steps in the records")
        adapter = ir["adapter_encode"] + ir["adapter_observe"] + ir["adapter_fingers"]
        parts = {
            # per control step
            "bullet_step": ir["bullet"],
            "drive": ir["drive"],
            "contact_forces": ir["contact_forces"],
            "motor_glue": ir["step_control"] - ir["bullet"] - ir["drive"] - ir["contact_forces"],
            "ik": ir["ik"],
            "observation": ir["snapshot"] + ir["evaluate"] + ir["tcp_glue"]
            + max(0, ir["env_step"] - ir["step_control"] - ir["ik"] - ir["snapshot"] - ir["evaluate"]),
            "decoder": ir["hidden_step"] - ir["env_step"],
            "adapter": adapter,
            "policy": ir["policy"],
            "record": ir["record"],
        }
        step_loop = sum(parts.values())
        per_episode = {
            "reset": ir["hidden_reset"],
            "adapter_setup": ir["adapter_make"] + ir["adapter_begin"],
        }
        store_open = ir["store_open"]
        other = total - step_loop - sum(per_episode.values())
        prof = {
            "instructions_total": total,
            "control_steps": steps,
            "episodes": episodes,
            "per_step": {k: v / steps for k, v in parts.items()},
            "per_step_total": step_loop / steps,
            "per_episode": {k: v / episodes for k, v in per_episode.items()},
            "outside_episodes": other,
            "store_open": store_open,
            "bullet_share": ir["bullet"] / step_loop,
            "bullet_share_of_env_step": ir["bullet"] / ir["env_step"],
            "functions": {k: names[k] for k in names},
        }

    def summarize_raw(path):
        raw = {}
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    raw.setdefault(r["task"], []).append(r)
        out = {}
        for task, runs in raw.items():
            out[task] = {
                "runs": len(runs),
                "env_us_per_step": statistics.median(r["env_us_per_step"] for r in runs),
                "raw_us_per_step": statistics.median(r["raw_us_per_step"] for r in runs),
                "raw_share": statistics.median(r["raw_share"] for r in runs),
                "identical": all(r["identical"] for r in runs),
                "all_env_us": [r["env_us_per_step"] for r in runs],
                "all_shares": [round(r["raw_share"], 4) for r in runs],
            }
        return out

    raw_summary = summarize_raw(a.raw)
    raw_base = summarize_raw(a.baseline_raw) if a.baseline_raw else None

    doc = {
        "measured": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "commit": a.commit,
        "nproc": a.nproc,
        "raw_steps": a.raw_steps,
        "callgrind": prof,
        "raw_bullet": raw_summary,
    }
    if raw_base:
        doc["raw_bullet_baseline"] = raw_base
    old = {}
    try:
        with open(a.json, encoding="utf-8") as f:
            old = json.load(f)
    except (OSError, ValueError):
        pass
    if prof is None and old.get("callgrind"):
        doc["callgrind"] = old["callgrind"]
        doc["callgrind_commit"] = old.get("callgrind_commit", old.get("commit"))
    else:
        doc["callgrind_commit"] = a.commit
    with open(a.json, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=1, sort_keys=True)
        f.write("\n")

    base = None
    if a.baseline:
        with open(a.baseline, encoding="utf-8") as f:
            b = json.load(f)
        base = b.get("callgrind")
        doc["baseline"] = {"label": a.baseline_label, "commit": b.get("callgrind_commit", b.get("commit")), "callgrind": base}
        with open(a.json, "w", encoding="utf-8") as f:
            json.dump(doc, f, indent=1, sort_keys=True)
            f.write("\n")
    lines = []
    p = doc["callgrind"]
    if p:
        st = p["per_step"]
        tot = p["per_step_total"]
        names = {
            "bullet_step": "Bullet step (`stepSimulation`: collision, constraint solve, integration; 5 per control step)",
            "drive": "implicit PD drive (joint-space inertia and solve, 5 per control step)",
            "contact_forces": "finger contact forces (manifold scan)",
            "motor_glue": "motor targets, finger caps, gravity compensation",
            "ik": "IK (one damped least-squares step)",
            "observation": "observation (snapshot, FK, task predicates, observation vector, TCP slices)",
            "decoder": "decoder (hidden contract, frame rotation)",
            "adapter": "adapter (encode, observe)",
            "policy": "policy (scripted expert)",
            "record": "record (stamp, validate, JSONL line; once per episode, shown per step)",
        }
        lines.append(
            f"callgrind, commit `{doc['callgrind_commit']}`: `actionshift run` over `configs/experiments/profile_mix.yaml` "
            f"(the tournament's 168 cells on the `maniskill` profile, one episode each, one thread): "
            f"{p['episodes']} episodes, {p['control_steps']:,} control steps, {p['instructions_total'] / 1e9:.2f} G instructions in all."
        )
        lines.append("")
        if base:
            bt = base["per_step_total"]
            lines.append(f"| part of a control step | instructions per step | share | {a.baseline_label} (commit `{doc['baseline']['commit']}`) | share |")
            lines.append("|---|---:|---:|---:|---:|")
            for k, label in names.items():
                bv = base["per_step"][k]
                lines.append(f"| {label} | {fmt_ir(st[k])} | {100 * st[k] / tot:.1f} % | {fmt_ir(bv)} | {100 * bv / bt:.1f} % |")
            lines.append(f"| **control step** | **{fmt_ir(tot)}** | 100 % | **{fmt_ir(bt)}** | 100 % |")
            lines.append(f"| Bullet's share of `Env::step` | | **{100 * p['bullet_share_of_env_step']:.1f} %** | | {100 * base['bullet_share_of_env_step']:.1f} % |")
        else:
            lines.append("| part of a control step | instructions per step | share |")
            lines.append("|---|---:|---:|")
            for k, label in names.items():
                lines.append(f"| {label} | {fmt_ir(st[k])} | {100 * st[k] / tot:.1f} % |")
            lines.append(f"| **control step** | **{fmt_ir(tot)}** | 100 % |")
            lines.append(f"| Bullet's share of `Env::step` | | **{100 * p['bullet_share_of_env_step']:.1f} %** |")
        pe = p["per_episode"]
        lines.append("")
        lines.append(
            f"Per episode besides its steps: reset (world rebuild) {fmt_ir(pe['reset'])}, adapter construction and "
            f"episode start {fmt_ir(pe['adapter_setup'])}; outside the episodes (plan, manifests, job set-up, 168 summaries) "
            f"{p['outside_episodes'] / 1e9:.2f} G in all, of which {p['store_open'] / 1e9:.2f} G is `ResultStore::open` "
            "looking for a sibling job to adopt records from (it reads every summary in the results directory, so its "
            "cost grows with the square of the jobs in one directory; it runs before a job's workers start)."
        )
        lines.append("")
    if raw_summary:
        lines.append(
            f"Raw-Bullet limit, commit `{a.commit}`, measured {doc['measured']}: `actionshift bench env --task T --raw-bullet "
            f"--steps {a.raw_steps} --json`, {max(r['runs'] for r in raw_summary.values())} runs per task (medians), "
            + ("under `nice -n -10` " if a.niced else "")
            + f"on the shared {a.nproc}-CPU machine (other engineers' builds running). The scripted grasp-and-lift's "
            "`Env::step` is timed, with the inputs the controller hands Bullet recorded; each episode is then rebuilt "
            "and the same bodies are stepped with those inputs and no controller work:"
        )
        lines.append("")
        if raw_base:
            lines.append(f"| task | `Env::step` [µs] | raw Bullet, same world [µs] | Bullet share of `Env::step` | replay bit-identical "
                         f"| {a.baseline_label}: `Env::step` [µs] | raw Bullet [µs] | share |")
            lines.append("|---|---:|---:|---:|---|---:|---:|---:|")
        else:
            lines.append("| task | `Env::step` [µs] | raw Bullet, same world [µs] | Bullet share of `Env::step` | replay bit-identical |")
            lines.append("|---|---:|---:|---:|---|")
        for task, r in raw_summary.items():
            row = (f"| {task} | {r['env_us_per_step']:.0f} | {r['raw_us_per_step']:.0f} | **{100 * r['raw_share']:.1f} %** "
                   f"| {'yes' if r['identical'] else 'NO'} |")
            if raw_base and task in raw_base:
                b = raw_base[task]
                row += f" {b['env_us_per_step']:.0f} | {b['raw_us_per_step']:.0f} | {100 * b['raw_share']:.1f} % |"
            lines.append(row)
        lines.append("")
    block = "\n".join(lines).rstrip() + "\n"
    with open(a.page, encoding="utf-8") as f:
        page = f.read()
    if BEGIN not in page or END not in page:
        sys.exit(f"sim_profile_report: {a.page}: markers {BEGIN} / {END} not found")
    head, rest = page.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(a.page, "w", encoding="utf-8") as f:
        f.write(head + BEGIN + "\n" + block + END + tail)


if __name__ == "__main__":
    main()
