"""Run the Markdown docs and the README as tests (Sybil).

```python blocks are executed in order, sharing one namespace per file; ``>>>`` examples inside
them are doctests whose printed output must match exactly (ELLIPSIS and NORMALIZE_WHITESPACE).
A block preceded by ``<!-- skip: next -->`` is not run (for shell commands shown as Python).
"""

from __future__ import annotations

from doctest import ELLIPSIS, NORMALIZE_WHITESPACE

from sybil import Sybil
from sybil.parsers.markdown import PythonCodeBlockParser, SkipParser

pytest_collect_file = Sybil(
    parsers=[
        PythonCodeBlockParser(doctest_optionflags=ELLIPSIS | NORMALIZE_WHITESPACE),
        SkipParser(),
    ],
    patterns=["*.md"],
).pytest()
