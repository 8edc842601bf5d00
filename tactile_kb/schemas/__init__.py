"""JSON Schemas (draft 2020-12) of every ``--json`` output of the ``tactile-kb`` command.

* ``classify.schema.json``: one line per object of ``classify --json`` and ``demo --json``;
* ``grasp.schema.json``: one line per object of ``grasp --json``;
* ``compile.schema.json``: the document of ``compile --json``;
* ``query.schema.json``: the document of ``query --json``.

A line for an object that failed is ``{"object": …, "error": {"kind": …, "message": …}}``
(the ``error`` definition of each schema).

Examples
--------
>>> sorted(schema_names())
['classify', 'compile', 'grasp', 'query']
>>> schema("classify")["title"]
'tactile-kb classify --json: one line per object'
"""

from __future__ import annotations

import importlib.resources
import json
from typing import Any

__all__ = ["schema", "schema_names"]

_SUFFIX = ".schema.json"


def schema_names() -> list[str]:
    """The commands that have a schema."""
    here = importlib.resources.files(__name__)
    return sorted(e.name[: -len(_SUFFIX)] for e in here.iterdir() if e.name.endswith(_SUFFIX))


def schema(name: str) -> dict[str, Any]:
    """The JSON Schema of ``tactile-kb NAME --json`` as a dictionary."""
    text = (importlib.resources.files(__name__) / f"{name}{_SUFFIX}").read_text(encoding="utf-8")
    data: dict[str, Any] = json.loads(text)
    return data
