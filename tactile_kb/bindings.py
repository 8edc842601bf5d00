"""Checking a rule file's feature bindings against the feature registry.

A rule file binds each proposition to a feature extractor by name with parameters, and each
class may report measures of the model. :func:`binding_problems` checks them all, located in
the file, without importing the geometry (so that ``tactile-kb validate`` starts quickly).
"""

from __future__ import annotations

from tactile_kb.errors import Problem
from tactile_kb.features.builtin import check_binding, measure_names
from tactile_kb.kb.rules import RuleSet

__all__ = ["binding_problems"]


def binding_problems(rules: RuleSet, *, missing: str = "error") -> list[Problem]:
    """Every proposition of ``rules`` whose feature binding is missing or wrong, located.

    A rule file binds each proposition to a feature extractor by name with parameters; the
    names are checked here against the feature registry (built-ins and plugins) and the
    parameters against the extractor's signature. A proposition with no binding is reported
    with severity ``missing``: an error for classifying objects, a warning for a rule file
    used only for its logic (``tactile-kb compile``, ``query``).
    """
    problems = []
    for i, prop in enumerate(rules.propositions):
        if prop.feature is None:
            problems.append(
                rules.problem(
                    ("propositions", i),
                    f"no feature decides proposition {prop.id!r}, so objects cannot be "
                    "classified with this file (add feature: NAME)",
                    severity=missing,
                )
            )
            continue
        message = check_binding(prop.feature.name, prop.feature.params)
        if message:
            # at the parameter's value when the message is about one, else at the feature
            where: tuple[str | int, ...] = ("propositions", i, "feature")
            bad = [k for k in prop.feature.params if f"parameter {k!r}" in message]
            if bad:
                where = (*where, "params", bad[0])
            if bad and "has no parameter" in message:  # at the unknown name
                problems.append(rules.source.problem(where, message, key=True))
            else:
                problems.append(rules.problem(where, message))
    known = measure_names()
    for i, cls in enumerate(rules.classes):
        for k, name in enumerate(cls.report):
            if name not in known:
                problems.append(
                    rules.problem(
                        ("classes", i, "report", k),
                        f"unknown measure {name!r} (known: {', '.join(known)})",
                    )
                )
    return problems
