"""Loading a compare JSON (`actionshift compare ... --out FILE`; docs/formats.md "Comparison") and indexing it."""
import json
import subprocess

SCHEMA = "1.0"


class Comparison:
    """The compare JSON with lookups. Cells are keyed (task, split, method label, backbone); comparisons
    (candidate, baseline, task, split, backbone). Nothing is recomputed: every accessor returns compare's objects."""

    def __init__(self, data, source=""):
        if data.get("schema_version") != SCHEMA:
            raise ValueError(f"{source}: compare schema_version {data.get('schema_version')!r}, this script reads {SCHEMA}")
        self.data = data
        self.source = source
        self.cells = data["cells"]
        self.comparisons = data["comparisons"]
        self.pairs = data["pairs"]
        self._cells = {(c["task"], c["split"], c["method"], c["backbone"]): c for c in self.cells}
        self._cmp = {(c["candidate"], c["baseline"], c["task"], c["split"], c["backbone"]): c for c in self.comparisons}

    def cell(self, task, split, method, backbone="expert"):
        """The cell, or None when it was not run."""
        return self._cells.get((task, split, method, backbone))

    def comparison(self, candidate, baseline, task, split, backbone="expert"):
        """The comparison candidate − baseline in one (task, split, backbone), or None."""
        return self._cmp.get((candidate, baseline, task, split, backbone))

    def cells_where(self, **kw):
        """Cells whose fields equal every keyword (e.g. task=..., backbone=...), in compare's order."""
        return [c for c in self.cells if all(c.get(k) == v for k, v in kw.items())]

    def comparisons_where(self, **kw):
        return [c for c in self.comparisons if all(c.get(k) == v for k, v in kw.items())]

    def values(self, field, cells=None):
        """The distinct values of a cell field, in first-seen order."""
        out = []
        for c in self.cells if cells is None else cells:
            if c[field] not in out:
                out.append(c[field])
        return out

    def seeds(self, cells=None):
        """Distinct seeds of the cells' per_seed lists, ascending."""
        return sorted({s["seed"] for c in (self.cells if cells is None else cells) for s in c["per_seed"]})

    def episodes(self, cells=None):
        """Episodes over the cells (a count of records, as compare reports them per cell)."""
        return sum(c["episodes"] for c in (self.cells if cells is None else cells))

    def episodes_per_seed(self, cells=None):
        """Distinct per-seed episode counts of the cells, ascending (e.g. [200] or [256])."""
        return sorted({s["episodes"] for c in (self.cells if cells is None else cells) for s in c["per_seed"]})

    def jobs(self, cells=None):
        return sorted({j for c in (self.cells if cells is None else cells) for j in c["jobs"]})

    def records(self):
        return self.data["inputs"]["records"]

    def input_dirs(self):
        return [d["dir"] for d in self.data["inputs"]["results_dirs"]]

    def notes(self):
        return [n for d in self.data["inputs"]["results_dirs"] for n in d.get("notes", [])]

    def paper_source(self):
        return self.data["inputs"]["paper"]["source"]

    def bootstrap(self):
        return self.data["bootstrap"]


def load_comparison(path):
    """Read a compare JSON file."""
    with open(path) as f:
        return Comparison(json.load(f), source=path)


def run_compare(binary, dirs, pairs_file=None, pairs=(), out=None):
    """Run `actionshift compare` (for tests and ad-hoc use; the page scripts are given the JSON file). Returns a Comparison."""
    cmd = [binary, "compare", *dirs]
    for p in pairs:
        cmd += ["--pair", p]
    if pairs_file:
        cmd += ["--pairs-from", pairs_file]
    if out:
        cmd += ["--out", out]
        subprocess.run(cmd, check=True)
        return load_comparison(out)
    r = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return Comparison(json.loads(r.stdout), source="actionshift compare")
