#!/usr/bin/env python3
"""Check of scripts/pages/dp_cost.py (the Diffusion Policy's cost beside the simulator step on the brittleness page):
it picks the benchmark median of the weight file's own network and sampler, divides by the simulator's step, and
refuses a file whose network the benchmark does not cover, a missing median or a non-DP file with one line naming
the file.
usage: tests/pages/dp_cost_test.py"""
import json
import os
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "pages", "dp_cost.py")


def asdp(path, dims, ddim=0):
    header = json.dumps({"task": "pick_cube", "arch": {"down_dims": dims, "diffusion_steps": 100, "act_horizon": 8},
                         "sampler_ddim_steps": ddim, "parameters": 1234}).encode()
    with open(path, "wb") as f:
        f.write(b"ASDPW\0\0\1" + struct.pack("<II", 1, len(header)) + header)


def bench(path, rows):
    b = []
    for fam, label, ms in rows:
        for agg, t in (("mean", ms + 1.0), ("median", ms), ("stddev", 0.1)):
            b.append({"name": f"{fam}/x_{agg}", "run_name": f"{fam}/0/0/iterations:64", "aggregate_name": agg,
                      "time_unit": "ms", "cpu_time": t, "label": label})
    with open(path, "w") as f:
        json.dump({"context": {"date": "d", "load_avg": [0.5, 0.4, 0.3], "num_cpus": 2}, "benchmarks": b}, f)


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


def main():
    bad = []
    with tempfile.TemporaryDirectory() as d:
        p = lambda n: os.path.join(d, n)  # noqa: E731
        bench(p("b.json"), [("BM_DpControlStep", "64/128/256 DDPM-100", 50.0), ("BM_DpChunk", "64/128/256 DDPM-100", 400.0),
                            ("BM_DpControlStep", "32/64/128 DDPM-100", 20.0), ("BM_DpChunk", "32/64/128 DDPM-100", 150.0)])
        with open(p("e.jsonl"), "w") as f:
            f.write(json.dumps({"task": "pick_cube", "steps_per_s_one_thread": 2500.0}) + "\n")
        asdp(p("paper.asdp"), [64, 128, 256])
        asdp(p("other.asdp"), [16, 32, 64])
        asdp(p("ddim.asdp"), [64, 128, 256], ddim=10)
        with open(p("junk.asdp"), "wb") as f:
            f.write(b"not a weight file at all")
        r = run("--command", "C", p("b.json"), p("e.jsonl"), p("paper.asdp"))
        if r.returncode != 0:
            bad.append(f"paper network: exit {r.returncode}: {r.stderr}")
        else:
            t = json.loads(r.stdout)["tasks"][0]
            want = {"control_step_ms": 50.0, "chunk_ms": 400.0, "sim_step_ms": 0.4, "sampler": "DDPM-100"}
            for k, v in want.items():
                if (abs(t[k] - v) > 1e-9) if isinstance(v, float) else t[k] != v:
                    bad.append(f"paper network: {k} = {t[k]}, want {v}")
            if abs(t["ratio"] - 125.0) > 1e-9:
                bad.append(f"paper network: ratio {t['ratio']}, want 125")
            if json.loads(r.stdout)["bench"] != "C":
                bad.append("--command is not recorded as bench")
        for name, needle in (("other.asdp", "16/32/64 DDPM-100"), ("ddim.asdp", "64/128/256 DDIM-10"),
                             ("junk.asdp", "not a Diffusion Policy weight file")):
            r = run(p("b.json"), p("e.jsonl"), p(name))
            msg = r.stderr.strip()
            if r.returncode == 0 or needle not in msg or "\n" in msg or not msg.startswith("dp_cost: "):
                bad.append(f"{name}: want one line with {needle!r} and a non-zero exit, got exit {r.returncode}: {msg!r}")
    for b in bad:
        print("FAIL", b)
    print("pages.dp_cost:", "FAIL" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
