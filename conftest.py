"""Run the Markdown docs and the README as tests (Sybil).

```python blocks are executed in order, sharing one namespace per file; ``>>>`` examples inside
them are doctests whose printed output must match exactly (ELLIPSIS and NORMALIZE_WHITESPACE).
A block preceded by ``<!-- skip: next -->`` is not run (for shell commands shown as Python).
Property tests (hypothesis) are derandomized when the environment variable ``CI`` is set.
"""

from __future__ import annotations

import os
from doctest import ELLIPSIS, NORMALIZE_WHITESPACE

from hypothesis import settings
from sybil import Sybil
from sybil.parsers.markdown import PythonCodeBlockParser, SkipParser

# CI runs each property test on the same examples every time (a failure there is always
# reproducible); developers' runs keep exploring new ones.
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

pytest_collect_file = Sybil(
    parsers=[
        PythonCodeBlockParser(doctest_optionflags=ELLIPSIS | NORMALIZE_WHITESPACE),
        SkipParser(),
    ],
    patterns=["*.md"],
).pytest()
