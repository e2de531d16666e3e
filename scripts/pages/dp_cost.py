#!/usr/bin/env python3
"""What a Diffusion Policy's control step costs beside the simulator's step, for scripts/brittleness: reads the
Google Benchmark JSON of `actionshift_dp_bench` (BM_DpControlStep and BM_DpChunk, medians over repetitions, CPU
time of one thread, random weights: the cost depends on the network's shape and the sampler, not on the values),
the JSON lines of `actionshift bench env --threads 1 --json` (one per task) and the weight files' headers, and
prints one JSON object (docs/formats.md "Diffusion Policy cost"): per weight file its network, sampler, the
matching benchmark rows and the simulator's step on the same task.
usage: scripts/pages/dp_cost.py [--command TEXT] DP_BENCH_JSON ENV_BENCH_JSONL WEIGHTS.asdp...
(--command: how the two benchmarks were run, recorded as `bench`)"""
import hashlib
import json
import os
import struct
import sys


def fail(where, why):
    sys.exit(f"dp_cost: {where}: {why}")


def asdp_header(path):
    """The JSON header of a `.asdp` file (docs/backbones.md "Weight format")."""
    with open(path, "rb") as f:
        head = f.read(16)
        if len(head) < 16 or head[:8] != b"ASDPW\0\0\1":
            fail(path, "not a Diffusion Policy weight file (magic)")
        (n,) = struct.unpack("<I", head[12:16])
        try:
            return json.loads(f.read(n).decode("utf-8"))
        except ValueError as e:
            fail(path, f"header: {e}")


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for b in iter(lambda: f.read(1 << 20), b""):
            h.update(b)
    return h.hexdigest()


def medians(bench_path):
    """{(family, label): cpu ms} of the median aggregates."""
    with open(bench_path) as f:
        j = json.load(f)
    out = {}
    for b in j.get("benchmarks", []):
        if b.get("aggregate_name") != "median":
            continue
        if b.get("time_unit") != "ms":
            fail(bench_path, f"{b['name']}: time unit {b.get('time_unit')!r}, expected ms")
        out[(b["run_name"].split("/")[0], b["label"])] = b["cpu_time"]
    if not out:
        fail(bench_path, "no median aggregates (run with --benchmark_repetitions >= 2)")
    return out, j.get("context", {})


def main():
    args = sys.argv[1:]
    command = "actionshift_dp_bench (medians, CPU time of one thread); actionshift bench env --threads 1 --json"
    if args[:1] == ["--command"]:
        if len(args) < 2:
            sys.exit("dp_cost: --command: missing its text")
        command, args = args[1], args[2:]
    if len(args) < 3:
        sys.exit("usage: " + __doc__.rsplit("usage: ", 1)[1])
    bench, ctx = medians(args[0])
    env = {}
    with open(args[1]) as f:
        for i, line in enumerate(f, 1):
            e = json.loads(line)
            env[e["task"]] = e
    rows = []
    for path in args[2:]:
        h = asdp_header(path)
        dims = "/".join(str(d) for d in h["arch"]["down_dims"])
        ddim = h.get("sampler_ddim_steps", 0)
        label = f"{dims} " + (f"DDIM-{ddim}" if ddim else f"DDPM-{h['arch']['diffusion_steps']}")
        step, chunk = bench.get(("BM_DpControlStep", label)), bench.get(("BM_DpChunk", label))
        if step is None or chunk is None:
            fail(args[0], f"no benchmark row {label!r} for {path} (the benchmark covers 64/128/256 and 32/64/128)")
        task = h["task"]
        if task not in env:
            fail(args[1], f"no `bench env` line for task {task}")
        sim_ms = 1000.0 / env[task]["steps_per_s_one_thread"]
        rows.append({"task": task, "weights": os.path.relpath(path), "sha256": sha256(path), "down_dims": h["arch"]["down_dims"],
                     "parameters": h["parameters"], "sampler": label.split(" ")[1], "act_horizon": h["arch"]["act_horizon"],
                     "chunk_ms": chunk, "control_step_ms": step, "sim_step_ms": sim_ms, "ratio": step / sim_ms})
    print(json.dumps({"format": "actionshift-dp-cost", "version": 1, "date": ctx.get("date"),
                      "load_avg": ctx.get("load_avg"), "num_cpus": ctx.get("num_cpus"),
                      "bench": command,
                      "tasks": rows}, indent=1))


if __name__ == "__main__":
    main()
