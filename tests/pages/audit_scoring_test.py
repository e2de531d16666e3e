#!/usr/bin/env python3
"""The audit benchmark's scoring (scripts/audit_report.py): which committed claims are wrong, for the
new model's `committed` block and for the previous model's fields; each rule has a case that it
decides and would decide otherwise without the rule. Prints 'N passed, N failed'."""
import copy
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import audit_report as R  # noqa: E402

TRUTH = {"contract": {"frame": "tool", "gripper_inverted": True, "lag": 3, "permutation": [1, 0, 2, 3, 4, 5],
                      "scale": [3.0, 1.0, 1.0, 1.0, 1.0, 0.5], "sign": [-1, 1, 1, 1, 1, 1], "target": "delta"},
         "rotation": "axis_angle", "gripper_range": "[-1, 1]", "action": "command"}


def field(identified, checked=True, resolved=True):
    return {"identified": identified, "checked": checked, "resolved": resolved}


def new_audit(status="MISMATCH", family="offgrid_lag", variant="clean", **committed):
    c = {"permutation": [None] * 6, "sign": [None] * 6, "scale_band": [None] * 6, "target": None, "frame": None,
         "lag": None, "gripper_inverted": None}
    c.update(committed)
    return {"status": status, "committed": c,
            "fields": {"gripper_range": field("[-1, 1]"), "rotation": field("axis_angle", checked=False, resolved=False),
                       "action": field("command")},
            "bench": {"case": {"case": "x", "family": family, "variant": variant, "task": "pick_cube", "backbone": "ppo"},
                      "truth": copy.deepcopy(TRUTH), "length": 200, "declared_as": "identity"}}


def old_audit(status="MISMATCH", perm="(1, 0, ?, ?, ?, ?)", scale="(?, ?, ?, ?, ?, ?)", lag=("4", True)):
    fields = {"permutation": field(perm), "sign": field("(-1, ?, ?, ?, ?, ?)"), "scale": field(scale),
              "target": field("delta"), "frame": field("tool", resolved=False), "lag": field(lag[0], resolved=lag[1]),
              "gripper_inverted": field("inverted (+1 closes)"), "gripper_range": field("[-1, 1]"),
              "rotation": field("axis_angle", checked=False, resolved=False), "action": field("command")}
    return {"status": status, "fields": fields,
            "bench": {"case": {"case": "y", "family": "offgrid_lag", "variant": "clean", "task": "pick_cube", "backbone": "ppo"},
                      "truth": copy.deepcopy(TRUTH), "length": 200, "declared_as": "identity"}}


CASES = [
    ("inconclusive commits nothing", lambda: R.wrong(new_audit("INCONCLUSIVE", sign=[1] * 6)) is None),
    ("right claims", lambda: R.wrong(new_audit(permutation=[1, 0, None, None, None, None], sign=[-1, None, None, None, None, None],
                                                lag=3, frame="tool", gripper_inverted=True)) is False),
    ("a wrong routing", lambda: R.wrong(new_audit(permutation=[0, None, None, None, None, None])) is True),
    ("a wrong sign", lambda: R.wrong(new_audit(sign=[1, None, None, None, None, None])) is True),
    ("a band holding the off-grid scale", lambda: R.wrong(new_audit(scale_band=[[1.7, 5.4]] + [None] * 5)) is False),
    ("a band without the scale", lambda: R.wrong(new_audit(scale_band=[[0.5, 2.0]] + [None] * 5)) is True),
    ("a grid lag for lag 3", lambda: R.wrong(new_audit(lag=4)) is True and R.offgrid_commit(new_audit(lag=4))),
    ("lag 3 named", lambda: R.wrong(new_audit(lag=3)) is False and not R.offgrid_commit(new_audit(lag=3))),
    ("a wrong frame", lambda: R.wrong(new_audit(frame="base")) is True),
    ("any commit on shuffled actions", lambda: R.wrong(new_audit("MISMATCH", family="no_relation")) is True),
    ("polarity from fingers that never move", lambda: R.wrong(new_audit(variant="constant_fingers", gripper_inverted=True)) is True),
    ("a resolved rotation that is not the recorded one",
     lambda: R.wrong(dict(new_audit(), fields={"gripper_range": field("[-1, 1]"), "rotation": field("euler_zyx"),
                                               "action": field("command")})) is True),
    ("previous model: right claims", lambda: R.wrong(old_audit(lag=("4", False))) is False),
    ("previous model: a grid lag for lag 3", lambda: R.wrong(old_audit()) is True and R.offgrid_commit(old_audit())),
    ("previous model: grid scales for 3.0", lambda: R.offgrid_commit(old_audit(scale="(1.5|2.0, ?, ?, ?, ?, ?)", lag=("4", False)))
     and R.wrong(old_audit(scale="(1.5|2.0, ?, ?, ?, ?, ?)", lag=("4", False))) is True),
    ("previous model: a wrong routing", lambda: R.wrong(old_audit(perm="(0, 1, ?, ?, ?, ?)", lag=("4", False))) is True),
]


def main():
    passed = failed = 0
    for name, check in CASES:
        try:
            ok = bool(check())
        except Exception as e:  # noqa: BLE001
            ok = False
            name += f" ({type(e).__name__}: {e})"
        if ok:
            passed += 1
        else:
            failed += 1
            print(f"FAIL: {name}")
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
