"""The engine: from the truth values of propositions to a class, and why.

* :meth:`Engine.classify` takes a full or partial assignment (a mapping id → bool, a bit
  string with ``-`` for unknown, or a numpy bool array of shape (n,)) and returns a
  :class:`Decision`: the class, its answer, the term of its reduced disjunction that matched,
  the phase after which the answer was certain; for ``otherwise`` the nearest classes by
  Hamming distance; for an assignment that breaks a connection, which one, by file line. A
  partial assignment is *certain* when every completion in r(L) gets the same answer.
* :meth:`Engine.classify_batch` classifies an (m, n) bool array: rows are packed into integers
  and looked up in a table of the 2ⁿ answers (n ≤ :data:`TABLE_MAX_N`), or the classes are
  evaluated column-wise with numpy.
* :meth:`Engine.decide` asks feature providers one proposition at a time, in phase order,
  skips propositions the connections already force, and stops as soon as one answer is left
  (the paper: "classification carried out in phases … manifests great economy").

When two classes overlap, the first in file order takes the shared minterms.

Examples
--------
>>> from tactile_kb.kb.compiler import PAPER_EXAMPLE, compile_rules
>>> kb = compile_rules(PAPER_EXAMPLE)
>>> d = kb.classify("1011011")
>>> d.label, d.answer, d.matched, d.phase
('cube', 'OBJECT IS A CUBE', 'A·B̄·C·D·Ē·F·G', 'V')
>>> kb.classify("1011010").nearest
(('cube', 1),)
>>> print(kb.classify("1010011").explanation)
1010011 violates line 13: F -> D (D is false, F is true)
>>> kb.classify({"A": True, "B": True}).answer
'OBJECT IS NOT RECOGNISED'
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from tactile_kb.errors import UsageError
from tactile_kb.kb.analysis import minimal_conflict
from tactile_kb.kb.expr import evaluate_columns, names
from tactile_kb.kb.notation import Cube, cube_text

if TYPE_CHECKING:
    from tactile_kb.kb.bdd import Node
    from tactile_kb.kb.knowledge import Knowledge

__all__ = [
    "FAST_MAX_N",
    "INCONSISTENT",
    "TABLE_MAX_N",
    "UNDECIDED",
    "Decision",
    "Engine",
    "ternary_closure",
]

INCONSISTENT = "inconsistent"
"""The label of an assignment that breaks a connection (batch index -1)."""
UNDECIDED = "undecided"
"""The label of a partial assignment that leaves more than one answer possible."""
TABLE_MAX_N = 22
"""Batch classification uses a lookup table of 2ⁿ answers up to this many propositions."""
FAST_MAX_N = 10
"""Up to this many propositions (and 61 classes) the engine precomputes, for each of the 3ⁿ
partial assignments, the set of answers its completions get: a single classification then
needs no BDD operation."""
CACHE_SIZE = 1 << 16
_TERNARY = str.maketrans("-", "2")
_KNOWN = str.maketrans("01-", "110")
_VALUE: dict[str, bool | None] = {"0": False, "1": True, "-": None}
_BIT_CHARS = frozenset("01-")

IntArray = np.ndarray[Any, np.dtype[np.int16]]


@dataclass(frozen=True)
class Decision:
    """What the engine decided for one assignment, and why.

    ``label`` is a class id, the rule set's ``otherwise`` id, :data:`INCONSISTENT` or (for a
    partial assignment that is not certain) :data:`UNDECIDED`; ``bits`` the assignment in
    declared order (``-`` unknown); ``values`` every proposition's value (``None`` unknown);
    ``evaluated`` the propositions whose value was given or asked for, in that order;
    ``phase`` the phase after which the answer was certain; ``matched`` the class term that
    matched (paper notation); ``nearest`` classes by Hamming distance (for ``otherwise``);
    ``violated`` the broken connections as ``line N: text``.
    """

    label: str
    answer: str
    bits: str
    values: dict[str, bool | None]
    evaluated: tuple[str, ...]
    phase: str | None
    certain: bool
    explanation: str
    matched: str | None = None
    nearest: tuple[tuple[str, int], ...] = ()
    violated: tuple[str, ...] = ()
    implied: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary."""
        return {
            "label": self.label,
            "answer": self.answer,
            "bits": self.bits,
            "values": dict(self.values),
            "evaluated": list(self.evaluated),
            "implied": list(self.implied),
            "phase": self.phase,
            "certain": self.certain,
            "explanation": self.explanation,
            "matched": self.matched,
            "nearest": [[label, dist] for label, dist in self.nearest],
            "violated": list(self.violated),
        }


@dataclass(frozen=True)
class _Term:
    mask: int
    value: int
    cube: Cube


def ternary_closure(values: np.ndarray[Any, Any], n: int, op: Any) -> np.ndarray[Any, Any]:
    """Extend a table over the 2ⁿ full assignments to the 3ⁿ partial ones.

    ``values[r]`` belongs to the assignment whose bits are those of r (first proposition most
    significant). The result is indexed by the base-3 number of the pattern (digit 0, 1, or
    2 for unknown: ``int(bits.replace("-", "2"), 3)``) and holds ``op`` (a numpy ufunc such
    as ``np.bitwise_or`` or ``np.add``) reduced over the pattern's completions.

    Examples
    --------
    >>> t = ternary_closure(np.array([1, 2, 4, 8]), 2, np.add)
    >>> [int(t[int(p, 3)]) for p in ("00", "01", "02", "12", "22")]
    [1, 2, 3, 12, 15]
    """
    a = values.reshape((2,) * n)
    for axis in range(n):
        both = op(a.take([0], axis=axis), a.take([1], axis=axis))
        a = np.concatenate([a, both], axis=axis)
    return a.reshape(-1)


@dataclass(frozen=True)
class _Lookup:
    """What one look-up found: the bits as integers, and the classes still possible."""

    bits: str
    x: int
    known_mask: int
    t: int
    known: dict[str, bool]
    answers: list[int]
    sets: bool


class Engine:
    """Classification over a compiled :class:`~tactile_kb.kb.compiler.KnowledgeBase`.

    Built by ``kb.engine``; use ``kb.classify``, ``kb.classify_batch`` and ``kb.decide``.
    """

    def __init__(self, kb: Knowledge) -> None:
        # a proxy: no reference cycle may hold BDD nodes, or CUDD's manager could be freed
        # before them by the garbage collector
        self.kb: Knowledge = weakref.proxy(kb)
        rules = kb.rules
        self.ids = kb.ids
        self.n = kb.n
        self.K = len(kb.classes)
        self.labels = [k.id for k in kb.classes] + [rules.otherwise_id]
        self.answers = [k.answer for k in kb.classes] + [rules.otherwise_answer]
        self.phase_of = {p.id: p.phase for p in rules.propositions}
        self.order: tuple[str, ...] = tuple(name for ph in rules.phases for name in ph.propositions)
        self.phase_ids = tuple(ph.id for ph in rules.phases)
        self.terms: list[list[list[_Term]]] = []
        for k in kb.classes:
            factors = []
            for sop in k.factors:
                factors.append([_Term(*self._mask(c), c) for c in sop])
            self.terms.append(factors)
        self._cache: dict[str, Decision] = {}
        self.conn_names = [
            sorted(names(c.expr), key=kb.index.__getitem__) for c in rules.connections
        ]
        self._table: IntArray | None = None
        self._wide: dict[int, IntArray] = {}
        index = kb.index
        self._powers = [3 ** (self.n - 1 - i) for i in range(self.n)]
        self._all_unknown = sum(2 * p for p in self._powers)
        self._phase_positions = [
            (ph.id, [index[name] for name in ph.propositions]) for ph in rules.phases
        ]
        self._answer_sets: list[int] | None = None
        self._satisfiable: list[bytes] = []  # per connection, by partial assignment
        if self.n <= FAST_MAX_N and self.K + 1 <= 62:
            self._build_fast()

    def _build_fast(self) -> None:
        """The answer set (a bit mask, bit K = otherwise) of every partial assignment, and
        whether each connection can still hold."""
        size = 1 << self.n
        cols = self._columns()
        table = self.table()
        bit = np.left_shift(np.int64(1), np.maximum(table, 0).astype(np.int64))
        masks = np.where(table >= 0, bit, 0).astype(np.int64)
        self._answer_sets = ternary_closure(masks, self.n, np.bitwise_or).tolist()
        self._satisfiable = [
            ternary_closure(
                evaluate_columns(c.expr, cols, size).astype(np.uint8),
                self.n,
                np.bitwise_or,
            ).tobytes()
            for c in self.kb.rules.connections
        ]

    def _mask(self, cube: Cube) -> tuple[int, int]:
        mask = value = 0
        for i, v in cube:
            bit = 1 << (self.n - 1 - i)
            mask |= bit
            if v:
                value |= bit
        return mask, value

    # ----------------------------------------------------------------- inputs

    def bits_of(self, assignment: Any) -> str:
        """The assignment as a bit string of length n (``-`` unknown); checks its form."""
        n, ids = self.n, self.ids
        if isinstance(assignment, str):
            if len(assignment) != n:
                raise UsageError(
                    f"bit string {assignment!r} has {len(assignment)} characters; "
                    f"the rule set has {n} propositions ({' '.join(ids)})"
                )
            if not _BIT_CHARS.issuperset(assignment):
                bad = next(ch for ch in assignment if ch not in _BIT_CHARS)
                raise UsageError(f"bit string {assignment!r}: {bad!r} is not 0, 1 or - (unknown)")
            return assignment
        if isinstance(assignment, np.ndarray):
            if assignment.shape != (n,):
                raise UsageError(
                    f"an assignment array must have shape ({n},), not {assignment.shape}; "
                    "use classify_batch for (m, n)"
                )
            if assignment.dtype != bool and not np.isin(assignment, (0, 1)).all():
                raise UsageError("an assignment array must hold booleans (or 0 and 1)")
            return "".join("1" if v else "0" for v in assignment.tolist())
        if isinstance(assignment, Mapping):
            out = ["-"] * n
            index = self.kb.index
            for name, value in assignment.items():
                if name not in index:
                    raise UsageError(
                        f"unknown proposition {name!r}; the propositions are {' '.join(ids)}"
                    )
                if value is None:
                    continue
                if not isinstance(value, bool | np.bool_) and value not in (0, 1):
                    raise UsageError(f"proposition {name!r}: {value!r} is not true/false/0/1")
                out[index[name]] = "1" if value else "0"
            return "".join(out)
        raise UsageError(
            "an assignment is a mapping id -> bool, a bit string or a numpy bool array, "
            f"not {type(assignment).__name__}"
        )

    def _values(self, bits: str) -> dict[str, bool | None]:
        return dict(zip(self.ids, map(_VALUE.__getitem__, bits), strict=True))

    # ----------------------------------------------------------------- answer sets

    def _pattern(self, known: Mapping[str, bool]) -> int:
        """The base-3 index of a partial assignment (``-`` is digit 2)."""
        t: int = self._all_unknown
        index: dict[str, int] = self.kb.index
        powers = self._powers
        for name, v in known.items():
            p = powers[index[name]]
            t -= p if v else 2 * p
        return t

    @staticmethod
    def _members(mask: int) -> list[int]:
        out = []
        while mask:
            low = mask & -mask
            out.append(low.bit_length() - 1)
            mask ^= low
        return out

    def possible(self, known: Mapping[str, bool]) -> list[int]:
        """Answers (class indices, ``K`` = otherwise) some completion of ``known`` gets;
        empty if ``known`` breaks the connections."""
        if self._answer_sets is not None:
            return self._members(self._answer_sets[self._pattern(known)])
        bdd, kb = self.kb.bdd, self.kb
        defs = dict(known)
        if not defs:
            out = [i for i, f in enumerate(kb.owned_bdds) if f != bdd.false]
            return [*out, self.K] if kb.gap_bdd != bdd.false else out
        out = [i for i, f in enumerate(kb.owned_bdds) if bdd.let(defs, f) != bdd.false]
        if bdd.let(defs, kb.gap_bdd) != bdd.false:
            out.append(self.K)
        return out

    def forced(self, known: Mapping[str, bool], name: str) -> bool | None:
        """The value the connections force on ``name`` given ``known``, if any."""
        if self._answer_sets is not None and name not in known:
            return self._forced_at(self._pattern(known), self.kb.index[name])
        bdd = self.kb.bdd
        rest: Node = bdd.let(dict(known), self.kb.r) if known else self.kb.r
        x = bdd.var(name)
        if rest & x == bdd.false:
            return False
        if rest & ~x == bdd.false:
            return True
        return None

    def _forced_at(self, t: int, i: int) -> bool | None:
        """:meth:`forced` for the pattern of base-3 index ``t``, proposition ``i`` unknown."""
        assert self._answer_sets is not None
        p = self._powers[i]
        if self._answer_sets[t - p] == 0:  # no completion with the proposition true
            return False
        if self._answer_sets[t - 2 * p] == 0:
            return True
        return None

    def _certain_phase_fast(self, bits: str, label: int) -> str | None:
        """:meth:`_certain_phase` on the answer sets: no BDD operation."""
        assert self._answer_sets is not None
        sets, powers = self._answer_sets, self._powers
        want = 1 << label
        t = self._all_unknown
        if sets[t] == want:
            return None
        for phase, positions in self._phase_positions:
            for i in positions:
                ch = bits[i]
                if ch == "1":
                    t -= powers[i]
                elif ch == "0":
                    t -= 2 * powers[i]
            if sets[t] == want:
                return phase
        return None  # pragma: no cover - the full assignment decides

    def _certain_phase(self, values: Mapping[str, bool | None], label: int) -> str | None:
        known: dict[str, bool] = {}
        if self.possible(known) == [label]:
            return None
        for ph in self.kb.rules.phases:
            for name in ph.propositions:
                v = values[name]
                if v is not None:
                    known[name] = v
            if self.possible(known) == [label]:
                return ph.id
        return None  # pragma: no cover - the full assignment decides

    def _violations(self, values: Mapping[str, bool | None]) -> list[int]:
        known = {k: v for k, v in values.items() if v is not None}
        bdd = self.kb.bdd
        single = [
            i for i, c in enumerate(self.kb.connection_bdds) if bdd.let(known, c) == bdd.false
        ]
        if single or len(known) == self.n:
            return single
        return minimal_conflict(bdd, bdd.cube(known), self.kb.connection_bdds)

    # ----------------------------------------------------------------- explanation

    def _match(self, k: int, x: int, known_mask: int) -> Cube:
        """The class's term (one cube per factor, merged) compatible with the known bits."""
        merged: dict[int, bool] = {}
        for factor in self.terms[k]:
            for t in factor:
                if (x ^ t.value) & t.mask & known_mask == 0:
                    merged.update(t.cube)
                    break
        return tuple(sorted(merged.items()))

    def _distance(self, k: int, x: int, known_mask: int) -> tuple[int, Cube]:
        """Hamming distance from the known bits to the class's nearest model, and its term."""
        total = 0
        nearest: dict[int, bool] = {}
        for factor in self.terms[k]:
            best = min(factor, key=lambda t: ((x ^ t.value) & t.mask & known_mask).bit_count())
            total += ((x ^ best.value) & best.mask & known_mask).bit_count()
            nearest.update(best.cube)
        return total, tuple(sorted(nearest.items()))

    def classify(self, assignment: Any) -> Decision:
        """Classify a full or partial assignment (see the module docstring)."""
        bits = self.bits_of(assignment)
        hit = self._cache.get(bits)
        if hit is not None:
            return hit
        decision = self._classify(bits)
        if len(self._cache) >= CACHE_SIZE:
            self._cache.clear()
        self._cache[bits] = decision
        return decision

    def _classify(
        self, bits: str, evaluated: tuple[str, ...] | None = None, asked_phase: str | None = None
    ) -> Decision:
        values = self._values(bits)
        lazily = evaluated is not None
        if evaluated is None:
            full = "-" not in bits
            evaluated = self.ids if full else tuple(v for v in self.ids if values[v] is not None)
        look = self._lookup(bits, values)
        common: dict[str, Any] = {"bits": bits, "values": values, "evaluated": evaluated}
        if not look.answers:
            return self._inconsistent(look, common)
        if len(look.answers) > 1:
            return self._undecided(look, common)
        label = look.answers[0]
        if lazily:
            phase = asked_phase
        elif look.sets:
            phase = self._certain_phase_fast(bits, label)
        else:
            phase = self._certain_phase(values, label)
        if label < self.K:
            return self._matched(label, phase, look, common)
        return self._otherwise(phase, look, common)

    def _lookup(self, bits: str, values: Mapping[str, bool | None]) -> _Lookup:
        """The classes still possible for ``bits``: a table look-up for small bases, BDD
        restrictions for large ones."""
        n = self.n
        x = int(bits.replace("-", "0"), 2) if n else 0
        known_mask = int(bits.translate(_KNOWN), 2) if n else 0
        sets = self._answer_sets
        if sets is not None:  # no BDD operation on this path
            t = int(bits.translate(_TERNARY), 3) if n else 0
            return _Lookup(bits, x, known_mask, t, {}, self._members(sets[t]), True)
        known = {k: v for k, v in values.items() if v is not None}
        return _Lookup(bits, x, known_mask, 0, known, self.possible(known), False)

    def _inconsistent(self, look: _Lookup, common: dict[str, Any]) -> Decision:
        """No class is possible: name the connections the values break."""
        values = common["values"]
        rules = self.kb.rules
        broken = []
        if look.sets:
            broken = [i for i, sat in enumerate(self._satisfiable) if not sat[look.t]]
        if not broken:
            broken = self._violations(values)
        cited = tuple(
            f"line {rules.connections[i].line}: {rules.connections[i].text}" for i in broken
        )
        why = []
        for i in broken:
            mentioned = [v for v in self.conn_names[i] if values[v] is not None]
            why.append(", ".join(f"{v} is {'true' if values[v] else 'false'}" for v in mentioned))
        text = "; ".join(f"{c} ({w})" for c, w in zip(cited, why, strict=True))
        return Decision(
            label=INCONSISTENT,
            answer="THE FEATURES CONTRADICT THE CONNECTIONS",
            phase=None,
            certain=True,
            explanation=f"{look.bits} violates {text}",
            violated=cited,
            **common,
        )

    def _undecided(self, look: _Lookup, common: dict[str, Any]) -> Decision:
        """More than one class is possible: say which, and what to evaluate next."""
        values = common["values"]
        names_ = [self.labels[i] for i in look.answers]
        index = self.kb.index

        def forced(v: str) -> bool | None:
            if look.sets:
                return self._forced_at(look.t, index[v])
            return self.forced(look.known, v)

        nxt = next((v for v in self.order if values[v] is None and forced(v) is None), None)
        ask = f"; evaluate {nxt} next" if nxt else ""
        return Decision(
            label=UNDECIDED,
            answer="UNDECIDED",
            phase=None,
            certain=False,
            explanation=f"{look.bits} leaves {len(look.answers)} answers possible: "
            f"{', '.join(names_)}{ask}",
            **common,
        )

    @staticmethod
    def _after(phase: str | None) -> str:
        return f", certain after phase {phase}" if phase else ", certain before any evaluation"

    def _matched(
        self, label: int, phase: str | None, look: _Lookup, common: dict[str, Any]
    ) -> Decision:
        """One class: cite the term of it that the values match."""
        k = self.kb.classes[label]
        term = cube_text(self._match(label, look.x, look.known_mask), self.ids)
        return Decision(
            label=k.id,
            answer=k.answer,
            phase=phase,
            certain=True,
            explanation=f"{k.answer}: {look.bits} matches {term} "
            f"(class {k.id!r}, line {k.line}){self._after(phase)}",
            matched=term,
            **common,
        )

    def _otherwise(self, phase: str | None, look: _Lookup, common: dict[str, Any]) -> Decision:
        """No class takes the values: the otherwise answer, with the nearest classes."""
        values = common["values"]
        rules = self.kb.rules
        near = sorted(
            ((self._distance(i, look.x, look.known_mask), i) for i in range(self.K)),
            key=lambda t: (t[0][0], t[1]),
        )
        nearest = tuple((self.labels[i], d) for (d, _), i in near)
        if near:
            (dist, cube), i = near[0]
            needs = [
                f"{self.ids[j]} {'true' if v else 'false'}"
                for j, v in cube
                if values[self.ids[j]] not in (None, v)
            ]
            hint = (
                f"; nearest: {self.labels[i]!r} at Hamming distance {dist}: "
                f"{cube_text(cube, self.ids)} needs {', '.join(needs)}"
            )
        else:
            hint = "; the rule set has no class"
        return Decision(
            label=rules.otherwise_id,
            answer=rules.otherwise_answer,
            phase=phase,
            certain=True,
            explanation=f"{rules.otherwise_answer}: no class takes {look.bits}{hint}",
            nearest=nearest,
            **common,
        )

    # ----------------------------------------------------------------- batch

    def table(self) -> IntArray:
        """The answer index of each of the 2ⁿ assignments (built on first use)."""
        if self._table is None:
            if self.n > TABLE_MAX_N:
                raise UsageError(f"no lookup table above {TABLE_MAX_N} propositions")
            self._table = self._evaluate(self._columns(), 1 << self.n)
        return self._table

    def _columns(self) -> dict[str, np.ndarray[Any, Any]]:
        """Each proposition's column over the 2ⁿ assignments (row r = the bits of r)."""
        ints = np.arange(1 << self.n, dtype=np.uint32)
        return {
            name: ((ints >> (self.n - 1 - i)) & 1).astype(bool) for i, name in enumerate(self.ids)
        }

    def _evaluate(self, cols: Mapping[str, Any], size: int) -> IntArray:
        rules = self.kb.rules
        ok = np.ones(size, dtype=bool)
        for c in rules.connections:
            ok &= evaluate_columns(c.expr, cols, size)
        out = np.full(size, self.K, dtype=np.int16)
        for i in range(self.K - 1, -1, -1):  # the first class in file order wins
            hit = evaluate_columns(rules.classes[i].expr, cols, size)
            out[hit] = i
        out[~ok] = -1
        return out

    def classify_batch(self, assignments: Any) -> IntArray:
        """Answer indices for an (m, n) array: class index, ``K`` = otherwise, -1 = violates."""
        arr = np.asarray(assignments)
        if arr.ndim != 2 or arr.shape[1] != self.n:
            raise UsageError(f"a batch must have shape (m, {self.n}), not {arr.shape}")
        if arr.dtype != bool:
            if arr.size and not np.isin(arr, (0, 1)).all():
                raise UsageError("a batch must hold booleans (or 0 and 1)")
            arr = arr.astype(bool)
        if self.n == 0:
            return np.full(arr.shape[0], self.table()[0], dtype=np.int16)
        if self.n > TABLE_MAX_N:
            cols = {name: arr[:, i] for i, name in enumerate(self.ids)}
            return self._evaluate(cols, arr.shape[0])
        table = self.table()
        packed = np.packbits(np.ascontiguousarray(arr), axis=1, bitorder="big")
        nbytes = packed.shape[1]
        shift = 8 * nbytes - self.n
        if nbytes <= 2:
            wide = self._wide_table(table, nbytes, shift)
            index = packed[:, 0] if nbytes == 1 else packed.view(">u2")[:, 0]
            return wide[index]
        index32 = np.zeros(arr.shape[0], dtype=np.uint32)
        for b in range(nbytes):
            index32 = (index32 << np.uint32(8)) | packed[:, b].astype(np.uint32)
        result: IntArray = table[index32 >> np.uint32(shift)]
        return result

    def _wide_table(self, table: IntArray, nbytes: int, shift: int) -> IntArray:
        # indexed by the packed bytes directly, so a batch needs no shift
        if nbytes not in self._wide:
            self._wide[nbytes] = table[np.arange(1 << (8 * nbytes)) >> shift]
        return self._wide[nbytes]

    # ----------------------------------------------------------------- lazy decision

    def decide(self, providers: Mapping[str, Callable[[], Any]]) -> Decision:
        """Ask ``providers[id]()`` in phase order until one answer is left.

        Propositions whose value the connections force are not asked (they are listed in
        ``implied``). The decision's ``phase`` is the phase of the last proposition asked.
        """
        known: dict[str, bool] = {}
        asked: list[str] = []
        implied: list[str] = []
        answers = self.possible(known)
        phase: str | None = None
        for name in self.order:
            if len(answers) <= 1:
                break
            forced = self.forced(known, name)
            if forced is not None:
                known[name] = forced
                implied.append(name)
                continue
            provider = providers.get(name)
            if provider is None:
                raise UsageError(
                    f"no provider for proposition {name!r} (phase {self.phase_of[name]})"
                )
            value = provider()
            if not isinstance(value, bool | np.bool_):
                raise UsageError(f"the provider of {name!r} returned {value!r}, not a bool")
            known[name] = bool(value)
            asked.append(name)
            phase = self.phase_of[name]
            answers = self.possible(known)
        bits = "".join("-" if v not in known else ("1" if known[v] else "0") for v in self.ids)
        d = self._classify(bits, evaluated=tuple(asked), asked_phase=phase)
        saved = f"; asked {len(asked)} of {self.n} propositions"
        if implied:
            saved += f", implied by the connections: {', '.join(implied)}"
        return replace(d, explanation=d.explanation + saved, implied=tuple(implied))
