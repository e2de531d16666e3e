#!/usr/bin/env python3
"""Belief trace: when does a pool-belief adapter identify the hidden contract, and what does the
delay-aware PPO backbone see in its history meanwhile? (diagnostic; docs/results/belief_trace.md)

Runs an `.asmlp` backbone, evaluated in numpy exactly as the C++ MlpPolicy evaluates it
(float32, tanh hidden layers, linear output clipped to [-1, 1]; a delay-aware file gets its own
last 4 emitted outputs, most recent first, zeros at episode start), through an adapter on the
contracts of a split, with a Python copy of the runner's episode loop (src/eval/episode_fn.cpp,
Context::run): episode i runs contract deal_permutation(seed, n, i div n)[i mod n] with env seed
episode_seed(seed, i div n) and adapter seed adapter_episode_seed(seed, i div n); per step: act, R from the observation, encode,
step, stop on a safety flag, response, observe, stop at the horizon. `--verify` runs the same
numpy policy through actionshift.evaluate() and compares the per-episode success flags.

Per step it records (privileged, diagnostic only):
  right    the adapter's raw action equals encode(true contract, intent, R, true tracked target)
           within 1e-9 (the belief acts as the truth would at this step);
  norm     |intent[:6]|, the emitted canonical pose action;
  hdis     |history the network reads - executed history| over the 4 x 7 history (for a reactive
           file: its emitted history, hypothetically), where executed = clip(decode(true contract, raw, R, true tracked target), -1, 1)
           (the canonical action entering the lag pipeline, what its training history holds).

History modes for the delay-aware network (--history):
  own        the C++ behaviour (its own emitted outputs);
  executed   the privileged executed canonical actions instead of the emitted ones;
  random:K   own outputs, except that the first K steps write uniform[-1, 1]^7 into the history;
  wrongid:K  own outputs, except that the first K steps write clip(decode(true contract, intent)),
             the action the intent would execute if sent unencoded (the pool's first hypothesis,
             the identity, is what the exact belief acts on before any evidence);
  zero:K     own outputs, but the history is cleared (zeros, as at an episode start) before step K.

--perturb K (with the oracle): the first K steps send the intent unencoded (what the exact belief
sends while its MAP is the pool's first hypothesis, the identity), the oracle's encoding after;
--perturb-part pose|gripper: only those channels sent unencoded, the others encoded right.

Usage (PYTHONPATH must reach the built module, e.g. build/python from the repository root):
  python3 scripts/belief_trace.py --backbone ppo-delay-aware --method exact_belief \
      --split reference_seen --pool reference9 --episodes 100 [--verify] [--json out.json]
"""

import argparse
import json
import os
import struct
import sys
import tempfile
import time

import numpy as np

import actionshift

M64 = (1 << 64) - 1
BACKBONES_DIR = os.environ.get("ACTIONSHIFT_BACKBONES_DIR",
                               os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "configs", "backbones"))


# ------------------------------------------------------------------ seeds (src/eval/job.cpp)
def splitmix64(x):
    z = (x + 0x9E3779B97F4A7C15) & M64
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M64
    return z ^ (z >> 31)


def episode_seed(seed, block):
    return splitmix64(splitmix64(splitmix64(seed & M64) ^ 0x696e6974737461) ^ (block & M64))


def deal_permutation(seed, n, block):
    s = splitmix64(splitmix64((seed ^ 0x6465616c696e67) & M64) ^ (block & M64))
    perm = list(range(n))
    for j in range(n - 1, 0, -1):
        s = splitmix64(s)
        k = s % (j + 1)
        perm[j], perm[k] = perm[k], perm[j]
    return perm


def adapter_episode_seed(seed, contract_episode):
    return splitmix64(splitmix64((seed ^ 0x61646170746572) & M64) ^ (contract_episode & M64))


# ------------------------------------------------------------------ the .asmlp MLP in numpy
def load_asmlp(path):
    b = open(path, "rb").read()
    if b[:8] != b"ASMLPW\x00\x01":
        raise ValueError(f"{path}: bad magic")
    version, hlen = struct.unpack("<II", b[8:16])
    if version != 1:
        raise ValueError(f"{path}: version {version}")
    if len(b) < 16 + hlen:
        raise ValueError(f"{path}: header: truncated: {len(b)} bytes, header length {hlen}")
    header = json.loads(b[16:16 + hlen].decode("utf-8"))
    payload = np.frombuffer(b[16 + hlen:], dtype="<f4")
    if payload.size != header["payload_floats"]:
        raise ValueError(f"{path}: payload has {payload.size} floats, header says {header['payload_floats']}")
    layers = header["layers"]
    at = 0

    def take(n):
        nonlocal at
        out = payload[at:at + n].astype(np.float32)
        at += n
        return out

    mean = take(layers[0])
    std = take(layers[0])
    W, B = [], []
    for i in range(len(layers) - 1):
        W.append(take(layers[i + 1] * layers[i]).reshape(layers[i + 1], layers[i]))
        B.append(take(layers[i + 1]))
    assert at == payload.size
    return header, mean, std, W, B


class NumpyMlp:
    """obs -> canonical action, as policy::MlpPolicy::act (float32 forward, output clipped)."""

    def __init__(self, path, history_mode="own", rng_seed=0):
        self.path = path
        self.header, self.mean, self.std, self.W, self.B = load_asmlp(path)
        self.history = int(self.header["history"])
        self.obs_dim = int(self.header["obs_dim"])
        self.history_mode = history_mode
        self.random_k = int(history_mode.split(":")[1]) if history_mode.startswith("random:") else 0
        self.wrong_k = int(history_mode.split(":")[1]) if history_mode.startswith("wrongid:") else 0
        self.zero_at = int(history_mode.split(":")[1]) if history_mode.startswith("zero:") else -1
        self.rng = np.random.default_rng(rng_seed)
        self.reset()

    def reset(self):
        self.hist = np.zeros((self.history, 7), dtype=np.float32)  # most recent first
        self.t = 0

    def forward(self, x):
        h = (x - self.mean) / self.std
        for i in range(len(self.W)):
            z = self.W[i] @ h + self.B[i]
            h = np.tanh(z) if i + 1 < len(self.W) else z
        return np.clip(h.astype(np.float64), -1.0, 1.0)

    def __call__(self, obs):
        x = np.asarray(obs, dtype=np.float64).astype(np.float32)
        if self.t == self.zero_at:
            self.hist[:] = 0.0
        if self.history:
            x = np.concatenate([x, self.hist.reshape(-1)])
        a = self.forward(x)
        if self.history:
            self.hist[1:] = self.hist[:-1].copy()
            if self.t < self.random_k:
                self.hist[0] = self.rng.uniform(-1.0, 1.0, 7).astype(np.float32)
            else:
                self.hist[0] = a.astype(np.float32)
        self.t += 1
        return a

    def overwrite_last(self, executed, wrong):
        """history mode `executed`: replace the entry just written by the executed canonical action;
        `wrongid:K`: for the first K steps, by `wrong` (what sending the intent unencoded would execute)."""
        if not self.history:
            return
        if self.history_mode == "executed":
            self.hist[0] = np.asarray(executed, dtype=np.float64).astype(np.float32)
        elif self.t - 1 < self.wrong_k:
            self.hist[0] = np.asarray(wrong, dtype=np.float64).astype(np.float32)


def backbone_path(task, name):
    if os.path.exists(name):
        return name
    return os.path.join(BACKBONES_DIR, f"{task}.{name}.asmlp")


# ------------------------------------------------------------------ the runner's loop, traced
def with_lag0(contract):
    d = contract.to_dict()
    d["lag"] = 0
    return actionshift.Contract.from_json(json.dumps(d))


def run_cell(task, backbone, method, split, pool, seed, episodes, history="own", profile="maniskill", perturb=0,
             perturb_part="all"):
    manifest = actionshift.load_manifest(split)
    contracts = manifest.contracts
    n = len(contracts)
    policy = NumpyMlp(backbone_path(task, backbone), history_mode=history, rng_seed=seed)
    envs = {}
    eps = []
    for i in range(episodes):
        ce = i // n
        ci = deal_permutation(seed, n, ce)[i % n]
        truth = contracts[ci]
        if ci not in envs:
            envs[ci] = actionshift.make(task, contract=truth, profile=profile)
        env = envs[ci]
        adapter = actionshift.make_adapter(method, task=task, pool=pool if method != "oracle" else None,
                                           truth=truth if method == "oracle" else None)
        truth0 = with_lag0(truth)
        tdec = actionshift.Decoder(truth0)  # privileged: the true tracked target, pre-FIFO decode
        obs, _ = env.reset(seed=episode_seed(seed, ce))
        policy.reset()
        adapter.begin_episode(adapter_episode_seed(seed, ce))
        emitted_hist = np.zeros((4, 7))
        executed_hist = np.zeros((4, 7))
        right, norm, hdis, adis, probe = [], [], [], [], []
        info = {}
        safety = "none"
        for step in range(env.horizon):
            net_hist = policy.hist if policy.history else emitted_hist  # what the network reads (reactive: hypothetical)
            hdis.append(float(np.linalg.norm(net_hist - executed_hist)))
            intent = np.asarray(policy(obs), dtype=np.float64)
            R = actionshift.tcp_rotation(obs, task)
            raw = np.asarray(adapter.encode(intent, R), dtype=np.float64)
            probe.append(bool(adapter.last_probe))
            T = tdec.tracked_target()
            true_raw = np.asarray(actionshift.encode(truth0, intent, R, T))
            if step < perturb:
                # the identity hypothesis' encoding (the intent sent as raw) on all 7 channels, on the
                # 6 pose channels only (gripper encoded right) or on the gripper only
                if perturb_part == "all":
                    raw = intent.copy()
                elif perturb_part == "pose":
                    raw = np.r_[intent[:6], raw[6]]
                else:
                    raw = np.r_[raw[:6], intent[6]]
            right.append(bool(np.max(np.abs(raw - true_raw)) <= 1e-9))
            wrong = np.clip(np.asarray(actionshift.decode(truth0, intent, R, T)), -1.0, 1.0)
            executed = np.clip(np.asarray(tdec.step(raw, R)), -1.0, 1.0)
            norm.append(float(np.linalg.norm(intent[:6])))
            adis.append(float(np.linalg.norm(intent - executed)))
            emitted_hist = np.vstack([intent, emitted_hist[:-1]])
            executed_hist = np.vstack([executed, executed_hist[:-1]])
            policy.overwrite_last(executed, wrong)
            nxt, _rew, _term, trunc, info = env.step(raw)
            if info["safety"] != "none":
                safety = info["safety"]
                break
            adapter.observe(raw, actionshift.tcp_response(obs, nxt, task), R)
            obs = nxt
            if trunc:
                break
        # the step from which the belief is right at every remaining step (None: never)
        t_right = None
        for t in range(len(right) - 1, -1, -1):
            if not right[t]:
                break
            t_right = t
        eps.append(dict(episode=i, contract=ci, lag=truth.lag, success=bool(info.get("success_once", False)),
                        safety=safety, steps=len(right), t_right=t_right, right=right, norm=norm, hdis=hdis,
                        adis=adis, probe=probe))
    return eps


def verify(task, backbone, method, split, pool, seed, episodes, mine, profile="maniskill"):
    """The same numpy policy through actionshift.evaluate(): per-episode success flags compared."""
    policy = NumpyMlp(backbone_path(task, backbone))
    with tempfile.TemporaryDirectory() as out:
        r = actionshift.evaluate(policy, task=task, split=split, method=method, seed=seed, episodes=episodes,
                                 out=out, backbone="python:belief_trace.NumpyMlp:" + os.path.basename(policy.path),
                                 pool=pool if method != "oracle" else None, profile=profile)
        recs = [json.loads(l) for l in open(r["jsonl_path"])]
    flags = {rec["episode_index"]: bool(rec["success_once"]) for rec in recs}
    theirs = [flags[i] for i in range(episodes)]
    ours = [e["success"] for e in mine]
    steps_theirs = {rec["episode_index"]: rec["steps"] for rec in recs}
    return dict(evaluate_rate=float(np.mean(theirs)), loop_rate=float(np.mean(ours)),
                flags_equal=sum(a == b for a, b in zip(theirs, ours)),
                steps_equal=sum(steps_theirs[e["episode"]] == e["steps"] for e in mine), episodes=episodes,
                job_id=r["job_id"])


# ------------------------------------------------------------------ summaries
BUCKETS = [("0", 0, 0), ("1-4", 1, 4), ("5-9", 5, 9), ("10-19", 10, 19), ("20-29", 20, 29), ("30-49", 30, 49)]


def summarize(eps):
    n = len(eps)
    s = dict(episodes=n, success=float(np.mean([e["success"] for e in eps])))
    tr = [e["t_right"] for e in eps]
    for t in (0, 5, 10, 20, 30):
        s[f"right_from_{t}"] = float(np.mean([x is not None and x <= t for x in tr]))
    s["right_never"] = float(np.mean([x is None for x in tr]))
    s["frac_steps_right"] = float(np.mean([np.mean(e["right"]) for e in eps]))
    cond = {}
    for name, lo, hi in BUCKETS + [("never", None, None)]:
        sel = [e for e in eps if (e["t_right"] is None if lo is None else (e["t_right"] is not None and lo <= e["t_right"] <= hi))]
        cond[name] = (len(sel), float(np.mean([e["success"] for e in sel])) if sel else None)
    s["success_by_t_right"] = cond
    s["norm_first10"] = float(np.mean([np.mean(e["norm"][:10]) for e in eps]))
    # variation: per episode, the mean over the 6 pose channels of the std over the first 10 steps is
    # not recorded per channel; use the std of the norm as a proxy plus the full-horizon norm
    s["norm_all"] = float(np.mean([np.mean(e["norm"]) for e in eps]))
    s["hdis_mean"] = float(np.mean([np.mean(e["hdis"]) for e in eps]))
    s["hdis_first10"] = float(np.mean([np.mean(e["hdis"][:10]) for e in eps]))
    s["adis_first10"] = float(np.mean([np.mean(e["adis"][:10]) for e in eps]))
    s["safety_stops"] = sum(e["safety"] != "none" for e in eps)
    s["safety_flags"] = {f: sum(e["safety"] == f for e in eps) for f in sorted({e["safety"] for e in eps}) if f != "none"}
    s["success_by_contract"] = {str(c): float(np.mean([e["success"] for e in eps if e["contract"] == c]))
                                for c in sorted({e["contract"] for e in eps})} if len({e["contract"] for e in eps}) <= 4 else None
    return s


def print_summary(label, s, by_lag=None):
    print(f"== {label}")
    print(f"   success {s['success']:.3f} over {s['episodes']} episodes; safety stops {s['safety_stops']} {s['safety_flags']}"
          + (f"; by contract {s['success_by_contract']}" if s["success_by_contract"] else ""))
    print("   belief right from step t onward: " +
          ", ".join(f"t<={t}: {s[f'right_from_{t}']:.2f}" for t in (0, 5, 10, 20, 30)) + f", never: {s['right_never']:.2f}"
          + f"; fraction of steps right {s['frac_steps_right']:.2f}")
    print("   success | step the belief became (and stayed) right: " +
          ", ".join(f"{k}: {v[1]:.2f} (n={v[0]})" if v[1] is not None else f"{k}: - (n=0)"
                    for k, v in s["success_by_t_right"].items()))
    print(f"   emitted |pose| first 10 steps {s['norm_first10']:.3f} (whole episode {s['norm_all']:.3f}); "
          f"|emitted - executed| first 10 {s['adis_first10']:.3f}; history disagreement mean {s['hdis_mean']:.3f} "
          f"(first 10 steps {s['hdis_first10']:.3f})")
    if by_lag:
        print("   by lag: " + ", ".join(f"lag {L}: success {v['success']:.3f} (n={v['episodes']}), never right {v['right_never']:.2f}"
                                      for L, v in by_lag.items()))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--task", default="push_cube")
    ap.add_argument("--backbone", default="ppo-delay-aware", help="ppo, ppo-delay-aware, ... or an .asmlp path")
    ap.add_argument("--method", default="exact_belief")
    ap.add_argument("--split", default="reference_seen")
    ap.add_argument("--pool", default="reference9")
    ap.add_argument("--seed", type=int, default=20260718)
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--history", default="own", help="own | executed | random:K (delay-aware files only)")
    ap.add_argument("--perturb", type=int, default=0, help="send the intent unencoded for the first K steps")
    ap.add_argument("--perturb-part", default="all", choices=["all", "pose", "gripper"])
    ap.add_argument("--verify", action="store_true", help="compare with actionshift.evaluate() (history own only)")
    ap.add_argument("--json", help="append the summary (one JSON line) to this file")
    args = ap.parse_args()
    t0 = time.time()
    eps = run_cell(args.task, args.backbone, args.method, args.split, args.pool, args.seed, args.episodes, args.history,
                   perturb=args.perturb, perturb_part=args.perturb_part)
    s = summarize(eps)
    lags = sorted({e["lag"] for e in eps})
    by_lag = {L: summarize([e for e in eps if e["lag"] == L]) for L in lags} if len(lags) > 1 else None
    pool = args.pool if args.method != "oracle" else "-"
    label = f"{args.task} {args.backbone} history={args.history} perturb={args.perturb}/{args.perturb_part} {args.method} pool={pool} {args.split} seed {args.seed}"
    print_summary(label, s, by_lag)
    print(f"   loop wall time {time.time() - t0:.1f} s")
    v = None
    if args.verify:
        if args.history != "own" or args.perturb:
            sys.exit("--verify needs --history own and no --perturb")
        t1 = time.time()
        v = verify(args.task, args.backbone, args.method, args.split, args.pool, args.seed, args.episodes, eps)
        print(f"   verify vs actionshift.evaluate(): evaluate {v['evaluate_rate']:.3f}, loop {v['loop_rate']:.3f}, "
              f"success flags equal {v['flags_equal']}/{v['episodes']}, step counts equal {v['steps_equal']}/{v['episodes']} "
              f"({time.time() - t1:.1f} s)")
    if v is not None and (v["flags_equal"] != v["episodes"] or v["steps_equal"] != v["episodes"]):
        print("belief_trace: the Python loop disagrees with actionshift.evaluate()", file=sys.stderr)
        sys.exit(1)
    if args.json:
        row = dict(task=args.task, backbone=args.backbone, history=args.history, perturb=args.perturb, perturb_part=args.perturb_part, method=args.method, pool=pool,
                   split=args.split, seed=args.seed, summary=s,
                   by_lag={str(k): v_ for k, v_ in by_lag.items()} if by_lag else None, verify=v,
                   t_right=[e["t_right"] for e in eps], success_flags=[e["success"] for e in eps])
        with open(args.json, "a") as f:
            f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    try:
        main()
    except (OSError, ValueError, KeyError, actionshift.InputError) as e:  # bad file, name or manifest: one line, exit 2
        print(f"belief_trace: {e}", file=sys.stderr)
        sys.exit(2)
