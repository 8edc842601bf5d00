"""tactile_kb: recognise a 3-D object by touch, and explain why.

The public API is what ``__all__`` lists (a test guards it); everything else may move. Names
are imported on first use (PEP 562), so ``import tactile_kb`` stays cheap and the command line
loads only what a subcommand needs.

Examples
--------
>>> import tactile_kb
>>> tactile_kb.load_rules("parallelepipeds").ids[:3]
('A', 'B', 'C')
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

# public name -> the module that defines it
_EXPORTS: dict[str, str] = {
    # errors
    **dict.fromkeys(
        [
            "ExplorationError",
            "ExpressionError",
            "GeometryError",
            "LayoutFileError",
            "ObjectError",
            "OpenModelError",
            "PluginError",
            "PluginUnavailableError",
            "Problem",
            "RecordError",
            "RuleFileError",
            "SourceError",
            "TactileKBError",
            "UsageError",
        ],
        "tactile_kb.errors",
    ),
    # knowledge: rule files → compiled model → decisions
    "RuleSet": "tactile_kb.kb.rules",
    "available_rule_sets": "tactile_kb.kb.rules",
    "load_rules": "tactile_kb.kb.rules",
    "parse_rules": "tactile_kb.kb.rules",
    "parse_expr": "tactile_kb.kb.expr",
    "CompiledClass": "tactile_kb.kb.knowledge",
    "Knowledge": "tactile_kb.kb.knowledge",
    "KnowledgeBase": "tactile_kb.kb.base",
    "compile_rules": "tactile_kb.kb.compiler",
    "Economy": "tactile_kb.kb.economy",
    "Decision": "tactile_kb.kb.engine",
    # touch: finger, worlds, explorers, records
    "Finger": "tactile_kb.touch.finger",
    "builtin_finger": "tactile_kb.touch.finger",
    "load_finger": "tactile_kb.touch.finger",
    "World": "tactile_kb.touch.world",
    "Explorer": "tactile_kb.touch.explorers",
    "WorldExplorer": "tactile_kb.touch.explorers",
    "available_explorers": "tactile_kb.touch.explorers",
    "get_explorer": "tactile_kb.touch.explorers",
    "load_object": "tactile_kb.objects",
    "Contact": "tactile_kb.record",
    "ExplorationRecord": "tactile_kb.record",
    "Layer": "tactile_kb.record",
    "Plane": "tactile_kb.record",
    "sample_record": "tactile_kb.touch.synthetic",
    # model: planes → polyhedron → features
    "Face": "tactile_kb.geometry.planes",
    "merge_planes": "tactile_kb.geometry.planes",
    "Polyhedron": "tactile_kb.geometry.polyhedron",
    "polyhedron_from_planes": "tactile_kb.geometry.polyhedron",
    "ObjectModel": "tactile_kb.geometry.model",
    "build_model": "tactile_kb.geometry.model",
    "Feature": "tactile_kb.features.builtin",
    "available_features": "tactile_kb.features.builtin",
    "get_feature": "tactile_kb.features.builtin",
    # act: grasping by the minimal angle of prehension
    "GraspCandidate": "tactile_kb.grasp.planner",
    "GraspPlan": "tactile_kb.grasp.planner",
    "plan_grasp": "tactile_kb.grasp.planner",
    # end to end
    "Classification": "tactile_kb.pipeline",
    "classify": "tactile_kb.pipeline",
    "classify_record": "tactile_kb.pipeline",
}

__all__ = [
    "Classification",
    "CompiledClass",
    "Contact",
    "Decision",
    "Economy",
    "ExplorationError",
    "ExplorationRecord",
    "Explorer",
    "ExpressionError",
    "Face",
    "Feature",
    "Finger",
    "GeometryError",
    "GraspCandidate",
    "GraspPlan",
    "Knowledge",
    "KnowledgeBase",
    "Layer",
    "LayoutFileError",
    "ObjectError",
    "ObjectModel",
    "OpenModelError",
    "Plane",
    "PluginError",
    "PluginUnavailableError",
    "Polyhedron",
    "Problem",
    "RecordError",
    "RuleFileError",
    "RuleSet",
    "SourceError",
    "TactileKBError",
    "UsageError",
    "World",
    "WorldExplorer",
    "__version__",
    "available_explorers",
    "available_features",
    "available_rule_sets",
    "build_model",
    "builtin_finger",
    "classify",
    "classify_record",
    "compile_rules",
    "get_explorer",
    "get_feature",
    "load_finger",
    "load_object",
    "load_rules",
    "merge_planes",
    "parse_expr",
    "parse_rules",
    "plan_grasp",
    "polyhedron_from_planes",
    "sample_record",
]

if TYPE_CHECKING:
    from tactile_kb.errors import (
        ExplorationError,
        ExpressionError,
        GeometryError,
        LayoutFileError,
        ObjectError,
        OpenModelError,
        PluginError,
        PluginUnavailableError,
        Problem,
        RecordError,
        RuleFileError,
        SourceError,
        TactileKBError,
        UsageError,
    )
    from tactile_kb.features.builtin import Feature, available_features, get_feature
    from tactile_kb.geometry.model import ObjectModel, build_model
    from tactile_kb.geometry.planes import Face, merge_planes
    from tactile_kb.geometry.polyhedron import Polyhedron, polyhedron_from_planes
    from tactile_kb.grasp.planner import GraspCandidate, GraspPlan, plan_grasp
    from tactile_kb.kb.base import KnowledgeBase
    from tactile_kb.kb.compiler import compile_rules
    from tactile_kb.kb.economy import Economy
    from tactile_kb.kb.engine import Decision
    from tactile_kb.kb.expr import parse_expr
    from tactile_kb.kb.knowledge import CompiledClass, Knowledge
    from tactile_kb.kb.rules import (
        RuleSet,
        available_rule_sets,
        load_rules,
        parse_rules,
    )
    from tactile_kb.objects import load_object
    from tactile_kb.pipeline import Classification, classify, classify_record
    from tactile_kb.record import Contact, ExplorationRecord, Layer, Plane
    from tactile_kb.touch.explorers import (
        Explorer,
        WorldExplorer,
        available_explorers,
        get_explorer,
    )
    from tactile_kb.touch.finger import Finger, builtin_finger, load_finger
    from tactile_kb.touch.synthetic import sample_record
    from tactile_kb.touch.world import World


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'tactile_kb' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return __all__
