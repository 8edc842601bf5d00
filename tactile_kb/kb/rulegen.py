"""Random rule files for tests and benchmarks.

:func:`generate_rules` writes a valid rule file of ``n`` propositions in clusters (features
that connections tie together, as in real knowledge bases), ``connections`` random
connections inside the clusters and ``classes`` conjunctions of literals. Satisfiability and
live classes are planted: one hidden assignment per class satisfies every connection, and the
class's literals are read off it, so no class is dead and r(L) is never empty. Overlaps and
gaps occur, as in hand-written files.

Examples
--------
>>> text = generate_rules(12, 6, 3, seed=1)
>>> text.splitlines()[0]
'name: generated-12-6-3-seed1'
"""

from __future__ import annotations

import random
from collections.abc import Callable

__all__ = ["generate_rules", "rules_text"]

Values = dict[str, bool]


def _lit(rng: random.Random, name: str) -> tuple[str, Callable[[Values], bool]]:
    if rng.random() < 0.3:
        return f"~{name}", lambda v: not v[name]
    return name, lambda v: v[name]


def _candidate(rng: random.Random, names: list[str]) -> tuple[str, Callable[[Values], bool]]:
    (ta, fa), (tb, fb), (tc, fc) = (_lit(rng, x) for x in rng.sample(names, 3))
    form = rng.randrange(7)
    if form == 0:
        return f"{ta} -> {tb}", lambda v: (not fa(v)) or fb(v)
    if form == 1:
        return f"~({ta} & {tb})", lambda v: not (fa(v) and fb(v))
    if form == 2:
        return f"{ta} = {tb}", lambda v: fa(v) == fb(v)
    if form == 3:
        return f"{ta} | {tb}", lambda v: fa(v) or fb(v)
    if form == 4:
        return f"{ta} -> {tb} | {tc}", lambda v: (not fa(v)) or fb(v) or fc(v)
    if form == 5:
        return f"{ta} = ({tb} & {tc})", lambda v: fa(v) == (fb(v) and fc(v))
    return f"{ta} & {tb} -> {tc}", lambda v: (not (fa(v) and fb(v))) or fc(v)


def generate_rules(
    n: int,
    connections: int,
    classes: int,
    *,
    seed: int = 0,
    group_size: int = 8,
    literals: tuple[int, int] = (3, 6),
) -> str:
    """The YAML text of a random rule file (see the module docstring).

    ``group_size`` propositions form a cluster; each connection ties 2–3 propositions of one
    cluster; each class is a conjunction of ``literals`` (min, max) literals from one or two
    clusters. Propositions are ``P00``, ``P01``, …; phase ``Ik`` holds cluster k.
    """
    rng = random.Random(seed)
    width = len(str(max(n - 1, 0)))
    ids = [f"P{i:0{width}d}" for i in range(n)]
    size = max(3, group_size)
    clusters = [ids[i : i + size] for i in range(0, n, size)]
    if len(clusters) > 1 and len(clusters[-1]) < 3:
        last = clusters.pop()
        clusters[-1] = clusters[-1] + last
    bias = {x: rng.choice((0.15, 0.85)) for x in ids}
    planted = [{x: rng.random() < bias[x] for x in ids} for _ in range(max(classes, 1))]
    texts: list[str] = []
    attempts = 0
    while len(texts) < connections and attempts < 10_000 * max(connections, 1):
        attempts += 1
        cluster = rng.choice([c for c in clusters if len(c) >= 3] or clusters)
        if len(cluster) < 3:
            break
        text, holds = _candidate(rng, cluster)
        if text not in texts and all(holds(v) for v in planted):
            texts.append(text)
    lines = [
        f"name: generated-{n}-{connections}-{classes}-seed{seed}",
        "description: a random rule file (tactile_kb.kb.rulegen)",
        "propositions:",
    ]
    lines += [f"  - {{id: {x}, text: proposition {x}}}" for x in ids]
    lines.append("connections:" if texts else "connections: []")
    lines += [f"  - '{t}'" for t in texts]
    lines.append("phases:")
    for k, cluster in enumerate(clusters):
        lines.append(f"  - {{id: I{k}, propositions: [{', '.join(cluster)}]}}")
    lines.append("classes:" if classes else "classes: []")
    for j in range(classes):
        values = planted[j]
        pool = list(rng.choice(clusters))
        if len(clusters) > 1 and rng.random() < 0.5:
            pool += rng.choice(clusters)
        pool = sorted(set(pool), key=ids.index)
        k = min(len(pool), rng.randint(*literals))
        chosen = sorted(rng.sample(pool, k), key=ids.index)
        when = " & ".join(x if values[x] else f"~{x}" for x in chosen)
        lines += [f"  - id: class{j}", f"    answer: CLASS {j}", f"    when: '{when}'"]
    lines += ["otherwise:", "  id: unknown", "  answer: NOT RECOGNISED", ""]
    return "\n".join(lines)


def rules_text(
    ids: list[str],
    connections: list[str],
    classes: list[str],
    *,
    phases: list[list[str]] | None = None,
    name: str = "test",
) -> str:
    """A rule file from its parts: class ``k`` is ``c{k}`` with answer ``CLASS k``.

    ``phases`` defaults to one phase per proposition, in declared order.

    Examples
    --------
    >>> print(rules_text(["A", "B"], ["A -> B"], ["A & B"]))  # doctest: +NORMALIZE_WHITESPACE
    name: test
    propositions:
      - {id: A, text: proposition A}
      - {id: B, text: proposition B}
    connections:
      - 'A -> B'
    phases:
      - {id: ph0, propositions: [A]}
      - {id: ph1, propositions: [B]}
    classes:
      - {id: c0, answer: CLASS 0, when: 'A & B'}
    otherwise: {id: other, answer: NOT RECOGNISED}
    """
    phases = phases if phases is not None else [[x] for x in ids]
    lines = [f"name: {name}", "propositions:"]
    lines += [f"  - {{id: {x}, text: proposition {x}}}" for x in ids]
    lines.append("connections:" if connections else "connections: []")
    lines += [f"  - '{c}'" for c in connections]
    lines.append("phases:")
    lines += [f"  - {{id: ph{k}, propositions: [{', '.join(p)}]}}" for k, p in enumerate(phases)]
    lines.append("classes:" if classes else "classes: []")
    lines += [f"  - {{id: c{k}, answer: CLASS {k}, when: '{w}'}}" for k, w in enumerate(classes)]
    lines.append("otherwise: {id: other, answer: NOT RECOGNISED}")
    return "\n".join(lines) + "\n"
