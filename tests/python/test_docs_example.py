"""docs/python.md's first example runs as printed: its output block is what this build prints."""
import contextlib
import io
import os
import re


def test_the_documented_example_prints_what_the_page_says(source_dir, tmp_path, monkeypatch):
    page = open(os.path.join(source_dir, "docs", "python.md")).read()
    m = re.search(r"## Example[^\n]*\n\n```python\n(.*?)```\n\n[^`]*?```\n(.*?)```", page, re.S)
    assert m, "docs/python.md: no example followed by its printed output"
    code, printed = m.group(1), m.group(2)
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "docs/python.md example", "exec"), {"__name__": "__doc_example__"})
    assert out.getvalue() == printed
