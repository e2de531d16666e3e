#!/usr/bin/env python3
"""A uniform random policy (protocol actionshift-policy-v1, docs/backbones.md), standard library only.

Every step it answers 7 canonical numbers drawn uniformly from [-1, 1] (the 6 pose channels and the
gripper), whatever the observation. It is the audit benchmark's "random" backbone
(scripts/audit_benchmark_logs): a log whose actions excite every channel but do no task.

Deterministic: the numbers of the k-th episode this process sees (the k-th reset, counted from 0) come
from random.Random(STREAM * 1000003 + k), so the same command on the same job writes the same log.
STREAM is a nonnegative integer given as `--stream STREAM` (default 0); the benchmark script draws one
per log from its set's seed.

    actionshift record ... --backbone "external:python3 scripts/audit_random_policy.py --stream 7" \
        --policy-files scripts/audit_random_policy.py
"""
import json
import random
import sys


def main(argv):
    stream = 0
    if len(argv) == 3 and argv[1] == "--stream" and argv[2].isdigit():
        stream = int(argv[2])
    elif len(argv) != 1:
        print("usage: audit_random_policy.py [--stream N]", file=sys.stderr)
        return 2
    episode = -1
    rng = None
    for line in sys.stdin:
        msg = json.loads(line)
        kind = msg.get("type")
        if kind == "hello":
            reply = {"type": "ready"}
        elif kind == "reset":
            episode += 1
            rng = random.Random(stream * 1000003 + episode)
            continue
        elif kind == "step":
            if rng is None:  # a step before any reset: treat it as episode 0
                episode = 0
                rng = random.Random(stream * 1000003)
            reply = {"action": [rng.uniform(-1.0, 1.0) for _ in range(7)]}
        else:
            print(f"audit_random_policy.py: unknown message type {kind!r}", file=sys.stderr)
            return 1
        sys.stdout.write(json.dumps(reply) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
