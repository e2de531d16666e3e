"""A Markdown table writer."""


def _cell(x):
    s = "—" if x is None else str(x)
    return s.replace("|", "\\|").replace("\n", " ")


def markdown(header, rows, align=None):
    """A Markdown table (a string ending in a newline). header: column titles; rows: lists of cells (None is "—");
    align: per column "l", "r" or "c" (default left)."""
    align = align or ["l"] * len(header)
    if len(align) != len(header):
        raise ValueError("align must have one entry per column")
    sep = {"l": "---", "r": "---:", "c": ":---:"}
    out = ["| " + " | ".join(_cell(h) for h in header) + " |", "|" + "|".join(sep[a] for a in align) + "|"]
    for r in rows:
        if len(r) != len(header):
            raise ValueError(f"row has {len(r)} cells, header {len(header)}: {r}")
        out.append("| " + " | ".join(_cell(x) for x in r) + " |")
    return "\n".join(out) + "\n"
