"""The README's Python examples run and print what the README shows (doctest), and
the tables of the README and the docs keep their shape."""

from __future__ import annotations

import doctest
import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"
DOCS = sorted((README.parent / "docs").glob("*.md"))


def test_readme_python_blocks_are_correct():
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 3
    parser = doctest.DocTestParser()
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    globs: dict = {}
    for i, src in enumerate(blocks):
        test = parser.get_doctest(src, globs, f"README block {i}", str(README), 0)
        assert test.examples, f"README python block {i} has no >>> examples"
        runner.run(test, clear_globs=False)
        globs.update(test.globs)  # the blocks form one session, as in the README
    res = runner.summarize(verbose=False)
    assert res.failed == 0, f"{res.failed} README example(s) failed (see the output above)"


def _cells(row: str) -> list[str]:
    """The cells of a Markdown table row (``\\|`` is a bar inside a cell)."""
    return [c.strip() for c in re.split(r"(?<!\\)\|", row.strip())[1:-1]]


def test_every_table_row_has_its_header_s_columns():
    """Every row of every Markdown table in the README and docs/ has as many cells as
    its header, and a second row of dashes (a table whose rows were replaced by
    another table's shows nine cells under a five-column header)."""
    assert DOCS
    tables = 0
    for path in [README, *DOCS]:
        lines = path.read_text(encoding="utf-8").splitlines()
        k = 0
        while k < len(lines):
            if not lines[k].startswith("|"):
                k += 1
                continue
            tables += 1
            header = _cells(lines[k])
            rule = _cells(lines[k + 1]) if k + 1 < len(lines) else []
            where = f"{path.name}:{k + 1}"
            assert len(rule) == len(header) and all(re.fullmatch(r":?-+:?", c) for c in rule), where
            k += 2
            while k < len(lines) and lines[k].startswith("|"):
                assert len(_cells(lines[k])) == len(header), f"{path.name}:{k + 1}: {lines[k][:60]}"
                k += 1
    assert tables >= 10
