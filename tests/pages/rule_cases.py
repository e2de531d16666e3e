"""Shared runner for the page-rule unit checks (tests/pages/*_verdict_test.py, brittleness_dp_claims_test.py).

A case is (status the rule must give, a phrase its reason must contain, a zero-argument call of the rule). The
call is usually a functools.partial, so a failure prints the arguments the rule was given."""


def run_cases(title, cases):
    """Run every case, print each failure and a count; return the process exit code (1 if any case failed)."""
    bad = 0
    for want, phrase, call in cases:
        status, why = call()
        if status != want or phrase not in why:
            print(f"FAILED: {call!r}\n  got {status!r} ({why})\n  want {want!r} with {phrase!r}")
            bad += 1
    print(f"{title}: {len(cases) - bad}/{len(cases)} cases as the page states")
    return 1 if bad else 0
