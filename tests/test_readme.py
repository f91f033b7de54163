"""The README's Python examples run and print what the README shows (doctest)."""

from __future__ import annotations

import doctest
import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


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
