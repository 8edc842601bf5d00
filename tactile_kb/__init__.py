"""tactile_kb: recognise a 3-D object by touch, and explain why.

The public API is what ``__all__`` lists; everything else may move.
"""

from __future__ import annotations

from tactile_kb.errors import (
    ExplorationError,
    ExpressionError,
    GeometryError,
    LayoutFileError,
    ObjectError,
    OpenModelError,
    PluginError,
    PluginUnavailableError,
    RecordError,
    RuleFileError,
    SourceError,
    TactileKBError,
    UsageError,
)
from tactile_kb.finger import Finger, builtin_finger
from tactile_kb.record import Contact, ExplorationRecord, Layer, Plane

__version__ = "0.1.0"

__all__ = [
    "Contact",
    "ExplorationError",
    "ExplorationRecord",
    "ExpressionError",
    "Finger",
    "GeometryError",
    "Layer",
    "LayoutFileError",
    "ObjectError",
    "OpenModelError",
    "Plane",
    "PluginError",
    "PluginUnavailableError",
    "RecordError",
    "RuleFileError",
    "SourceError",
    "TactileKBError",
    "UsageError",
    "__version__",
    "builtin_finger",
]
