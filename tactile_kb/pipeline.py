"""End to end: explore an object, model it, decide its propositions phase by phase, name it.

The data flows one way, each stage a plain value::

    mesh ─explorer─▶ ExplorationRecord ─build_model─▶ ObjectModel ─features─▶ truth values
    rule file ─load_rules─▶ RuleSet ─compile_rules─▶ KnowledgeBase ─decide─▶ Decision

Exploration is lazy where the rule file's phases allow: a proposition whose feature needs only
contact (phase I of the paper: "there is contact between the object and the finger") is
decided after the first touch; the rest of the object is explored only when a later phase
asks for a proposition that needs the whole model.

Examples
--------
>>> from tactile_kb.solids import box
>>> result = classify(box(0.08, 0.08, 0.08))
>>> result.decision.answer
'OBJECT IS A CUBE'
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from tactile_kb.bindings import binding_problems
from tactile_kb.completion import completing
from tactile_kb.errors import RuleFileError, UsageError
from tactile_kb.features.builtin import get_feature, measure, measure_names
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.kb.base import KnowledgeBase
from tactile_kb.kb.compiler import compile_rules
from tactile_kb.kb.engine import Decision
from tactile_kb.kb.rules import RuleSet, load_rules
from tactile_kb.objects import ObjectLike, object_name
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.explorers import Explorer, Goal, get_explorer
from tactile_kb.touch.finger import Finger

__all__ = [
    "Classification",
    "binding_problems",
    "classify",
    "classify_record",
    "explorer_for",
    "knowledge_base",
]

RulesLike = str | Path | RuleSet | KnowledgeBase


@dataclass(frozen=True)
class Classification:
    """The outcome of classifying one object: the decision and everything behind it."""

    object: str
    decision: Decision
    record: ExplorationRecord
    model: ObjectModel
    seconds: float
    rules: RuleSet = field(repr=False)
    """The rule set that decided."""
    contacts_per_phase: dict[str, int] = field(default_factory=dict)
    """Touches made by the time each rule-file phase was decided (cumulative)."""

    @property
    def planes(self) -> int:
        """Distinct planes touched, the table included (an assumed top is not counted)."""
        return sum(1 for f in self.model.faces if f.source != "assumed")

    @property
    def measures(self) -> dict[str, float | int | None]:
        """Every measure of the model (faces, vertices, edges, sides, volume, height)."""
        return {name: measure(self.model, name) for name in measure_names()}

    @property
    def reported(self) -> dict[str, float | int | None]:
        """The measures the decided class reports (its ``report:`` list in the rule file)."""
        return {name: measure(self.model, name) for name in _reports(self.rules, self.decision)}

    @property
    def answer(self) -> str:
        """The answer with the reported measures, e.g. ``OBJECT IS A PRISM (sides = 5)``."""
        extra = ", ".join(f"{k} = {_fmt(v)}" for k, v in self.reported.items())
        return f"{self.decision.answer} ({extra})" if extra else self.decision.answer

    def summary(self) -> dict[str, Any]:
        """The JSON object of ``tactile-kb classify --json`` (one line per object).

        Its schema is ``tactile_kb/schemas/classify.schema.json``: ``answer`` is the
        bare answer and ``report`` the answer with the measures its class reports (as the
        text output prints it); ``touches`` counts sensor OFF→ON events and ``contacts``
        every contact recorded (touches and slides); ``ending`` is how the completion ended,
        ``unreachable`` names what it could not touch (a face flat on the table, one the
        object shadows), never guessed, and ``budget`` which budget ran out.
        """
        return {
            "object": self.object,
            "answer": self.decision.answer,
            "report": self.answer,
            "label": self.decision.label,
            "bits": self.decision.bits,
            "propositions": dict(self.decision.values),
            "touches": self.record.touches,
            "contacts": len(self.record.contacts),
            "planes": self.planes,
            "path_length": round(self.record.path_length, 6),
            "seconds": round(self.seconds, 4),
            "phase": self.decision.phase,
            "touches_per_phase": dict(self.contacts_per_phase),
            "explanation": self.decision.explanation,
            "reported": self.reported,
            "measures": self.measures,
            "notes": list(self.record.notes),
            "ending": self.record.ending,
            "unreachable": list(self.record.unreachable),
            "budget": self.record.budget,
        }


def _reports(rules: RuleSet, decision: Decision) -> tuple[str, ...]:
    """The measures the decided class reports; none for ``otherwise`` and contradictions."""
    ids = {c.id for c in rules.classes}
    return rules.rule_class(decision.label).report if decision.label in ids else ()


def _fmt(value: float | int | None) -> str:
    if value is None:
        return "unknown"
    return str(value) if isinstance(value, int) else f"{value:.4g}"


@lru_cache(maxsize=32)
def _compiled(path: str, mtime_ns: int) -> KnowledgeBase:
    return compile_rules(Path(path))


def knowledge_base(rules: RulesLike) -> KnowledgeBase:
    """Compile ``rules`` (a packaged name, a file, a RuleSet) once; a KnowledgeBase passes through.

    Every proposition must be bound to a registered feature with valid parameters; a bad
    binding raises :class:`~tactile_kb.errors.RuleFileError` at the binding's line.
    """
    if isinstance(rules, KnowledgeBase):
        kb = rules
    elif isinstance(rules, RuleSet):
        kb = compile_rules(rules)
    else:
        ruleset = load_rules(rules)
        p = Path(ruleset.file)
        kb = _compiled(str(p), p.stat().st_mtime_ns) if p.is_file() else compile_rules(ruleset)
    _check_bindings(kb.rules)
    return kb


def _check_bindings(rules: RuleSet) -> None:
    problems = binding_problems(rules)
    if problems:
        raise RuleFileError(problems, rules.source.excerpt(problems[0].line, problems[0].column))


class _Evidence:
    """Explores lazily and evaluates features on the model built from what was explored."""

    def __init__(
        self, advance: Callable[[Goal], ExplorationRecord], record: ExplorationRecord | None
    ):
        self._advance = advance
        self._record = record
        self._model: ObjectModel | None = None
        self._model_of: int = -1

    @property
    def record(self) -> ExplorationRecord:
        if self._record is None:
            self._record = self._advance("contact")
        return self._record

    def model(self, goal: Goal) -> ObjectModel:
        if goal == "complete" and not self.record.complete:
            self._record = self._advance("complete")
        rec = self.record
        key = id(rec)
        if self._model is None or self._model_of != key:
            # A model open only at the top (the 4-sensor finger never feels a top) is closed
            # at the highest touch; the model says so in ``assumed_top``. One open elsewhere
            # (a side the finger could not touch) is closed at the farthest touches that way
            # (``assumed_reach``); the record's ending says what stayed open.
            self._model = build_model(rec, assume_top=True, assume_reach=True)
            self._model_of = key
        return self._model


def _decide(kb: KnowledgeBase, evidence: _Evidence) -> tuple[Decision, dict[str, int]]:
    per_phase: dict[str, int] = {}
    providers: dict[str, Callable[[], bool]] = {}
    for prop in kb.rules.propositions:
        assert prop.feature is not None  # checked by knowledge_base()
        feature = get_feature(prop.feature.name)
        goal: Goal = "contact" if feature.requires == "contact" else "complete"
        params: Mapping[str, Any] = prop.feature.params

        def provide(
            feature: Any = feature,
            goal: Goal = goal,
            params: Mapping[str, Any] = params,
            phase: str = prop.phase,
        ) -> bool:
            value = bool(feature.fn(evidence.model(goal), **params))
            per_phase[phase] = evidence.record.touches
            return value

        providers[prop.id] = provide
    return kb.decide(providers), per_phase


def explorer_for(explorer: str | Explorer) -> Explorer:
    """The explorer named (or given), with the model-driven completion attached
    (:func:`tactile_kb.completion.completing`): how :func:`classify` and the command line
    explore."""
    return completing(get_explorer(explorer))


def classify(
    obj: ObjectLike,
    *,
    rules: RulesLike = "parallelepipeds",
    explorer: str | Explorer = "stepper",
    finger: Finger | str = "33",
    noise: float = 0.0,
    seed: int | None = 0,
) -> Classification:
    """Explore ``obj`` (a trimesh mesh or a mesh file) by touch and classify it with ``rules``.

    Parameters
    ----------
    obj
        The object: a ``trimesh.Trimesh`` or an STL/OBJ/PLY path, in metres.
    rules
        A packaged rule set name (``"parallelepipeds"``, ``"polyhedra"``), a YAML file, a
        loaded :class:`~tactile_kb.kb.rules.RuleSet` or a compiled KnowledgeBase.
    explorer
        An explorer name (``"stepper"``, ``"mujoco"`` when installed) or instance.
    finger
        ``"33"``, ``"4"``, a layout YAML file or a :class:`~tactile_kb.touch.finger.Finger`.
    noise
        σ of the contact-position noise, metres.
    seed
        Makes the exploration (noise, drop-outs) reproducible.
    """
    if noise < 0:
        raise UsageError(f"--noise must be ≥ 0 metres, got {noise}")
    t0 = time.perf_counter()
    kb = knowledge_base(rules)
    session = explorer_for(explorer).session(obj, finger=finger, seed=seed, noise=noise)
    evidence = _Evidence(session.advance, None)
    decision, per_phase = _decide(kb, evidence)
    # Explore no further than the decision needed, unless its class reports measures of the
    # whole object (the n of a prism): those need the complete model.
    model = evidence.model("complete" if _reports(kb.rules, decision) else "contact")
    record = evidence.record
    seconds = time.perf_counter() - t0
    return Classification(object_name(obj), decision, record, model, seconds, kb.rules, per_phase)


def classify_record(
    record: ExplorationRecord, *, rules: RulesLike = "parallelepipeds"
) -> Classification:
    """Classify a saved exploration record without exploring again."""
    t0 = time.perf_counter()
    kb = knowledge_base(rules)

    def no_more(goal: Goal) -> ExplorationRecord:
        return record

    evidence = _Evidence(no_more, record)
    decision, per_phase = _decide(kb, evidence)
    model = evidence.model("contact")
    seconds = time.perf_counter() - t0
    return Classification(record.object, decision, record, model, seconds, kb.rules, per_phase)
