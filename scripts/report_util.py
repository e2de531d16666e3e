"""Small helpers shared by the scripts that write docs/results pages. Standard library only."""
import re


def cpu_text(times_line):
    """' , CPU time N s' from a bash `times` line ("2m19.630s 0m10.540s"), or '' when not given."""
    t = re.findall(r"(\d+)m([\d.]+)s", times_line)
    return "" if not t else f", CPU time {sum(int(m) * 60 + float(x) for m, x in t):.0f} s (user + system)"
