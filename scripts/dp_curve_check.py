#!/usr/bin/env python3
"""Compares the loss curve of a Diffusion Policy re-training with a committed curve, point by point,
to the last bit.

A re-train of a committed .asdp (scripts/ppo_reproduce) takes hours; its checkpoint header holds the
curve so far (the mean noise-prediction loss of every 50 iterations, as the committed curve file
docs/results/dp_<task>.curve.jsonl does). Each logged loss is a function of the whole training state,
so a curve equal to the committed one at every logged iteration so far means the re-train has followed
the committed run so far; the first unequal loss is where it left it.

usage: scripts/dp_curve_check.py RUN COMMITTED
  RUN        a `train dp --checkpoint` file, or a curve .jsonl written by train dp
  COMMITTED  the committed curve (.jsonl: one {"iteration", "loss", "seconds"} per line)
exit 0: every logged loss of RUN equals COMMITTED's at that iteration (prints how many, up to where);
     1: the first that differs is printed; 2: unreadable input (one line naming the file and why).
"""
import json
import struct
import sys

CHECKPOINT_MAGIC = b"ASDPCKP\0"


def fail(path, why):
    print(f"dp_curve_check: {path}: {why}", file=sys.stderr)
    sys.exit(2)


def read_curve(path):
    """[(iteration, loss)] of a checkpoint header or a curve .jsonl (lines without a loss are skipped)."""
    try:
        with open(path, "rb") as f:
            head = f.read(16)
            if head[:8] == CHECKPOINT_MAGIC:
                if len(head) < 16:
                    fail(path, "truncated checkpoint header")
                n = struct.unpack("<I", head[12:16])[0]
                raw = f.read(n)
                if len(raw) != n:
                    fail(path, "truncated checkpoint header")
                return [(int(p[0]), float(p[1])) for p in json.loads(raw)["curve"]]
            f.seek(0)
            points = []
            for number, line in enumerate(f, 1):
                if not line.strip():
                    continue
                row = json.loads(line)
                if "loss" in row:
                    points.append((int(row["iteration"]), float(row["loss"])))
            return points
    except OSError as e:
        fail(path, e.strerror or str(e))
    except (ValueError, KeyError, TypeError, IndexError) as e:
        fail(path, f"not a train dp checkpoint or curve ({type(e).__name__}: {e})")


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().split("\n\n")[-1], file=sys.stderr)
        sys.exit(2)
    run_path, committed_path = sys.argv[1], sys.argv[2]
    run, committed = read_curve(run_path), dict(read_curve(committed_path))
    if not run:
        print(f"{run_path}: no logged loss yet")
        return 0
    for iteration, loss in run:
        want = committed.get(iteration)
        if want is None:
            print(f"{run_path}: iteration {iteration} is not in {committed_path}")
            return 1
        if loss != want:
            print(f"{run_path}: DIFFERS at iteration {iteration}: loss {loss!r}, committed {want!r} "
                  f"(relative {abs(loss - want) / abs(want):.1e})")
            return 1
    print(f"{run_path}: all {len(run)} logged losses so far (iterations {run[0][0]}-{run[-1][0]}) equal, to the last bit, "
          f"those of {committed_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
