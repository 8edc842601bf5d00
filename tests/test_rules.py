"""Tests of tactile_kb.kb.rules: loading, every located error kind, the packaged knowledge base."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
import trimesh

from tactile_kb.errors import RuleFileError, UsageError
from tactile_kb.kb.expr import And, Not, Var, evaluate, parse_expr
from tactile_kb.kb.rules import (
    FeatureBinding,
    RuleSet,
    available_rule_sets,
    load_rules,
    parse_rules,
    rules_directories,
)
from tactile_kb.yaml_source import load_yaml

BASE = """\
name: demo
description: A small base.
propositions:
  - id: A
    text: There is contact
    feature: contact
  - id: B
    text: Surface is curved
    feature: {name: surface_curved, params: {tolerance_deg: 20}}
  - id: C
    text: Surface is plane
connections:
  - B = ~C
  - expr: C -> A
    note: a plane needs contact
phases:
  - id: I
    title: contact
    propositions: [A]
  - id: II
    propositions: [B, C]
classes:
  - id: flat
    answer: OBJECT IS FLAT
    when: A & C
  - id: round_thing
    answer: OBJECT IS ROUND
    when: A & B
otherwise:
  id: unknown
  answer: OBJECT IS NOT RECOGNISED
"""


def at(text: str, needle: str, nth: int = 0, shift: int = 0) -> tuple[int, int]:
    """1-based line and column of the ``nth`` occurrence of ``needle`` (plus ``shift``)."""
    idx = -1
    for _ in range(nth + 1):
        idx = text.index(needle, idx + 1)
    idx += shift
    line = text.count("\n", 0, idx) + 1
    return line, idx - (text.rfind("\n", 0, idx) + 1) + 1


def where(text: str, needle: str, nth: int = 0, shift: int = 0) -> str:
    line, col = at(text, needle, nth, shift)
    return f"demo.yaml:{line}:{col}"


def edit(old: str, new: str, text: str = BASE) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


def problems(text: str) -> list[str]:
    with pytest.raises(RuleFileError) as info:
        parse_rules(text, file="demo.yaml")
    return [str(p) for p in info.value.problems]


def only_problem(text: str) -> str:
    found = problems(text)
    assert len(found) == 1, found
    return found[0]


# --------------------------------------------------------------------------- a valid file


def test_valid_file_loads_into_the_interface() -> None:
    rules = parse_rules(BASE, file="demo.yaml")
    assert isinstance(rules, RuleSet)
    assert (rules.name, rules.description, rules.file) == ("demo", "A small base.", "demo.yaml")
    assert rules.ids == ("A", "B", "C")
    a, b, c = rules.propositions
    assert (a.id, a.text, a.phase, a.line) == ("A", "There is contact", "I", 4)
    assert a.feature == FeatureBinding("contact", {}, *at(BASE, "feature: contact", shift=9))
    assert b.feature == FeatureBinding(
        "surface_curved", {"tolerance_deg": 20}, *at(BASE, "surface_curved")
    )
    assert c.feature is None
    assert (b.phase, c.phase) == ("II", "II")
    first, second = rules.connections
    assert (first.index, first.text, first.note) == (0, "B = ~C", "")
    assert (first.line, first.column) == at(BASE, "B = ~C")
    assert first.expr == parse_expr("B = ~C")
    assert (second.text, second.note) == ("C -> A", "a plane needs contact")
    assert (second.line, second.column) == at(BASE, "C -> A")
    assert second.path == ("connections", 1, "expr")
    assert [(p.id, p.title, p.propositions, p.line) for p in rules.phases] == [
        ("I", "contact", ("A",), at(BASE, "id: I\n")[0]),
        ("II", "", ("B", "C"), at(BASE, "id: II")[0]),
    ]
    flat, round_thing = rules.classes
    assert (flat.id, flat.answer, flat.name, flat.text) == (
        "flat",
        "OBJECT IS FLAT",
        "flat",
        "A & C",
    )
    assert flat.expr == And((Var("A"), Var("C")))
    assert round_thing.name == "round thing"
    assert flat.line == at(BASE, "id: flat")[0]
    assert (rules.otherwise_id, rules.otherwise_answer) == ("unknown", "OBJECT IS NOT RECOGNISED")
    assert rules.proposition("B") is b
    assert rules.rule_class("flat") is flat


def test_lookup_of_unknown_names_is_a_usage_error() -> None:
    rules = parse_rules(BASE, file="demo.yaml")
    with pytest.raises(UsageError, match="no proposition 'Z'; its propositions: A, B, C"):
        rules.proposition("Z")
    with pytest.raises(UsageError, match="no class 'cube'; its classes: flat, round_thing"):
        rules.rule_class("cube")


def test_rule_set_problem_and_locate_helpers() -> None:
    rules = parse_rules(BASE, file="demo.yaml")
    conn = rules.connections[1]
    p = rules.problem(conn.path, "redundant", severity="warning", offset=5)
    assert str(p) == f"{where(BASE, 'C -> A', shift=5)}: warning: connections[1].expr: redundant"
    assert rules.locate(("classes", 1, "id")) == at(BASE, "round_thing")
    assert str(rules.problem(("classes", 0), "dead")).startswith(where(BASE, "id: flat"))


def test_yaml_11_words_stay_strings_and_work_as_ids() -> None:
    text = BASE.replace("id: A", "id: no").replace("[A]", "[no]").replace("C -> A", "off -> no")
    text = (
        text.replace("id: B", "id: on")
        .replace("[B, C]", "[on, off]")
        .replace("B = ~C", "on = ~off")
    )
    text = text.replace("id: C", "id: off").replace("when: A & C", "when: no & off")
    text = text.replace("when: A & B", "when: no & on")
    rules = parse_rules(text, file="demo.yaml")
    assert rules.ids == ("no", "on", "off")
    assert rules.classes[0].expr == And((Var("no"), Var("off")))


def test_constant_and_null_forms() -> None:
    text = edit("    when: A & B", "    when: true")
    text = edit("    when: A & C", "    when: 0", text)
    rules = parse_rules(text, file="demo.yaml")
    assert [c.text for c in rules.classes] == ["0", "true"]
    text = edit("  - B = ~C\n  - expr: C -> A\n    note: a plane needs contact\n", "\n")
    assert parse_rules(text, file="demo.yaml").connections == ()


def test_multi_line_and_block_scalars_parse() -> None:
    text = edit("    when: A & B", "    when: >\n      A &\n      B")
    text = edit("  - B = ~C", "  - B =\n    ~C", text)
    rules = parse_rules(text, file="demo.yaml")
    assert rules.classes[1].expr == And((Var("A"), Var("B")))
    assert rules.connections[0].expr == parse_expr("B = ~C")


# --------------------------------------------------------------------------- error kinds


def test_yaml_syntax_error_is_located() -> None:
    text = edit("  - id: C\n", "\t- id: C\n")
    assert only_problem(text) == (
        f"{where(text, chr(9))}: YAML syntax error: found character '\\t' that cannot start any token"
    )


def test_duplicate_key_is_located_at_the_second_key() -> None:
    text = edit("    text: Surface is plane\n", "    text: Surface is plane\n    text: again\n")
    first = at(text, "text: Surface is plane")[0]
    assert only_problem(text) == (
        f"{where(text, 'text: again')}: propositions[2].text: duplicate key 'text' (first at line {first})"
    )


def test_octal_looking_id_stays_a_string_and_is_rejected() -> None:
    text = edit("  - id: C\n", "  - id: 0777\n")
    found = problems(text)
    assert (
        f"{where(text, '0777')}: propositions[2].id: '0777' is not an id: use a letter or an identifier ([A-Za-z_][A-Za-z0-9_]*)"
        in found
    )


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("12", "an id must be a string, not the number 12 (quote it)"),
        ("1.5", "an id must be a string, not the number 1.5 (quote it)"),
        ("true", "an id must be a string, not the boolean true (quote it)"),
        ("'true'", "'true' is a constant and cannot be an id"),
        ("'A B'", "'A B' is not an id: use a letter or an identifier ([A-Za-z_][A-Za-z0-9_]*)"),
        ("[C]", "an id must be a string, not a list (quote it)"),
    ],
)
def test_bad_ids(value: str, message: str) -> None:
    text = edit("  - id: C\n", f"  - id: {value}\n")
    assert f"{where(text, value)}: propositions[2].id: {message}" in problems(text)


def test_unknown_field_is_located_at_its_key() -> None:
    text = edit("    text: Surface is plane\n", "    text: Surface is plane\n    colour: red\n")
    assert only_problem(text) == f"{where(text, 'colour')}: propositions[2].colour: unknown field"


def test_missing_field_is_located_at_its_mapping() -> None:
    text = edit("    answer: OBJECT IS FLAT\n", "")
    assert only_problem(text) == f"{where(text, 'id: flat')}: classes[0].answer: field required"


WRONG_TYPES = [
    # (text replaced, replacement, where the value starts in it, path, message)
    (
        "text: Surface is plane",
        "text: 12",
        6,
        "propositions[2].text",
        "Input should be a valid string",
    ),
    (
        "text: Surface is plane",
        "text: ''",
        6,
        "propositions[2].text",
        "String should have at least 1 character",
    ),
    ("answer: OBJECT IS FLAT", "answer:", 7, "classes[0].answer", "Input should be a valid string"),
    (
        "when: A & C",
        "when: 7",
        6,
        "classes[0].when",
        "an expression must be a string, not the number 7",
    ),
    (
        "when: A & C",
        "when: [A]",
        6,
        "classes[0].when",
        "an expression must be a string, not a list",
    ),
    ("name: demo", "name: a b", 6, "name", "'a b' is not a rule-set name ([A-Za-z0-9_.-]+)"),
    (
        "propositions: [B, C]",
        "propositions: B",
        14,
        "phases[1].propositions",
        "Input should be a valid list",
    ),
]


@pytest.mark.parametrize(("old", "new", "shift", "path", "message"), WRONG_TYPES)
def test_wrong_types(old: str, new: str, shift: int, path: str, message: str) -> None:
    text = edit(old, new)
    assert only_problem(text) == f"{where(text, new, shift=shift)}: {path}: {message}"


@pytest.mark.parametrize(
    ("value", "needle", "path", "message"),
    [
        (
            "5",
            "5",
            "propositions[2].feature",
            "a feature is a name or a mapping with a name and params, not the number 5",
        ),
        (
            "[contact]",
            "[contact]",
            "propositions[2].feature",
            "a feature is a name or a mapping with a name and params, not a list",
        ),
        (
            "{name: contact, params: 3}",
            "3}",
            "propositions[2].feature.params",
            "Input should be a valid dictionary",
        ),
        ("{params: {}}", "{params", "propositions[2].feature.name", "field required"),
        (
            "{name: 'bad name'}",
            "'bad name'",
            "propositions[2].feature.name",
            "'bad name' is not a feature name",
        ),
        (
            "{name: 4}",
            "4}",
            "propositions[2].feature.name",
            "a feature name must be a string, not the number 4",
        ),
        (
            "{name: contact, tolerance: 3}",
            "tolerance: 3",
            "propositions[2].feature.tolerance",
            "unknown field",
        ),
    ],
)
def test_feature_binding_shape(value: str, needle: str, path: str, message: str) -> None:
    text = edit(
        "    text: Surface is plane\n", f"    text: Surface is plane\n    feature: {value}\n"
    )
    assert only_problem(text) == f"{where(text, needle)}: {path}: {message}"


def test_unknown_id_in_an_expression_points_inside_it() -> None:
    text = edit("    when: A & B", "    when: A & (B | Cx)")
    assert only_problem(text) == (
        f"{where(text, 'Cx')}: classes[1].when: unknown proposition 'Cx'; did you mean 'C'?"
    )
    text = edit("  - B = ~C", "  - B = ~Q")
    assert only_problem(text) == f"{where(text, 'Q')}: connections[0]: unknown proposition 'Q'"
    text = edit("  - B = ~C", "  - b = ~C")
    assert only_problem(text) == (
        f"{where(text, 'b = ~C')}: connections[0]: unknown proposition 'b'; did you mean 'B'?"
    )


def test_every_unknown_id_is_reported() -> None:
    text = edit("    when: A & B", "    when: X & B & Y | X")
    assert problems(text) == [
        f"{where(text, 'X')}: classes[1].when: unknown proposition 'X'",
        f"{where(text, 'Y')}: classes[1].when: unknown proposition 'Y'",
        f"{where(text, 'X', nth=1)}: classes[1].when: unknown proposition 'X'",
    ]


@pytest.mark.parametrize(
    ("expr", "bad", "message"),
    [
        ("A & | C", "|", "expected an id, a constant, '~' or '(' but found '|'"),
        ("A & (C", "(", "unbalanced '(': it is never closed"),
        ("A & C)", ")", "unbalanced ')': no '(' to close"),
        ("A $ C", "$", "unexpected character '$'"),
        ("A C", " C", "expected an operator but found 'C'"),
        ("A = C = A", "= A", "chained '=' is ambiguous: add parentheses"),
    ],
)
@pytest.mark.parametrize("quote", ["", "'", '"'])
def test_malformed_expression_points_at_the_bad_token(
    expr: str, bad: str, message: str, quote: str
) -> None:
    text = edit("    when: A & C", f"    when: {quote}{expr}{quote}")
    shift = 1 if bad.startswith(" ") else 0
    line, col = at(text, f"when: {quote}{expr}")
    col += len(f"when: {quote}") + expr.index(bad) + shift
    assert only_problem(text) == f"demo.yaml:{line}:{col}: classes[0].when: {message}"


def test_missing_operand_at_the_end_points_after_the_expression() -> None:
    text = edit("  - expr: C -> A", "  - expr: 'C ->'")
    line, col = at(text, "'C ->'", shift=len("'C ->"))
    assert only_problem(text) == (
        f"demo.yaml:{line}:{col}: connections[1].expr: "
        "missing operand after '->': expected an id, a constant, '~' or '('"
    )


def test_positions_inside_multi_line_and_block_scalars() -> None:
    folded = edit("    when: A & B", "    when: >\n      A &\n      (B | Zed)")
    assert (
        only_problem(folded)
        == f"{where(folded, 'Zed')}: classes[1].when: unknown proposition 'Zed'"
    )
    literal = edit("    when: A & B", "    when: |\n      A &\n        (B | Zed)")
    assert (
        only_problem(literal)
        == f"{where(literal, 'Zed')}: classes[1].when: unknown proposition 'Zed'"
    )
    plain = edit("  - B = ~C", "  - B =\n      ~Q")
    assert only_problem(plain) == f"{where(plain, 'Q')}: connections[0]: unknown proposition 'Q'"
    quoted = edit("  - B = ~C", "  - 'B = \n     ~Q'")
    assert only_problem(quoted) == f"{where(quoted, 'Q')}: connections[0]: unknown proposition 'Q'"
    escaped = edit("  - B = ~C", '  - "B =\\t~Q"')
    assert (
        only_problem(escaped) == f"{where(escaped, 'Q')}: connections[0]: unknown proposition 'Q'"
    )


@pytest.mark.parametrize("style", ["plain", "single", "double"])
def test_scalar_positions_agree_with_the_one_line_locator(style: str) -> None:
    quote = {"plain": "", "single": "'", "double": '"'}[style]
    text = f"when: {quote}A & (Bb | ~Cc) -> D{quote}\n"
    src = load_yaml(text, file="x.yaml")
    rules_like = RuleSet("x", "", "x.yaml", (), (), (), (), "u", "U", src)
    for offset in range(len(src.data["when"])):
        assert rules_like.locate(("when",), offset) == src.locate_in_scalar(("when",), offset)


def test_proposition_in_no_phase() -> None:
    text = edit("propositions: [B, C]", "propositions: [B]")
    assert (
        only_problem(text)
        == f"{where(text, 'id: C', shift=4)}: propositions[2].id: proposition 'C' is in no phase"
    )


def test_proposition_in_two_phases_and_twice_in_one() -> None:
    text = edit("propositions: [A]", "propositions: [A, C]")
    assert only_problem(text) == (
        f"{where(text, 'C]', nth=1)}: phases[1].propositions[1]: "
        f"proposition 'C' is also in phase 'I' (line {at(text, 'C]')[0]})"
    )
    text = edit("propositions: [B, C]", "propositions: [B, C, B]")
    assert only_problem(text) == (
        f"{where(text, 'B]')}: phases[1].propositions[2]: "
        f"proposition 'B' is again (line {at(text, 'B, C')[0]})"
    )


def test_phase_naming_an_unknown_proposition() -> None:
    text = edit("propositions: [A]", "propositions: [A, Bx]")
    assert only_problem(text) == (
        f"{where(text, 'Bx')}: phases[0].propositions[1]: unknown proposition 'Bx'; did you mean 'B'?"
    )


def test_empty_phase() -> None:
    text = edit("classes:\n", "  - id: III\n    propositions: []\nclasses:\n")
    assert (
        only_problem(text)
        == f"{where(text, '[]')}: phases[2].propositions: phase 'III' names no proposition"
    )


@pytest.mark.parametrize(
    ("old", "new", "needle", "nth", "path", "what", "first"),
    [
        ("  - id: C\n", "  - id: B\n", "id: B", 1, "propositions[2].id", "proposition", "id: B"),
        ("  - id: II\n", "  - id: I\n", "id: I\n", 1, "phases[1].id", "phase", "id: I\n"),
        (
            "  - id: round_thing\n",
            "  - id: flat\n",
            "id: flat",
            1,
            "classes[1].id",
            "class",
            "id: flat",
        ),
    ],
)
def test_duplicate_ids(
    old: str, new: str, needle: str, nth: int, path: str, what: str, first: str
) -> None:
    text = edit(old, new)
    found = problems(text)
    name = new.split("id: ")[1].strip()
    line = at(text, first)[0]
    expected = f"{where(text, needle, nth=nth, shift=4)}: {path}: duplicate {what} id {name!r} (first at line {line})"
    assert expected in found, found


def test_class_id_equal_to_the_otherwise_id() -> None:
    text = edit("  id: unknown\n", "  id: flat\n")
    line = at(text, "id: flat", nth=1)[0]
    assert only_problem(text) == (
        f"{where(text, 'flat')}: classes[0].id: class id 'flat' is also the otherwise id (line {line})"
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "the rule file is empty: it needs name, propositions, phases, classes, otherwise"),
        (
            "- a\n",
            "the rule file is a list, not a mapping: it needs name, propositions, phases, classes, otherwise",
        ),
        (
            "just text\n",
            "the rule file is 'just text', not a mapping: it needs name, propositions, phases, classes, otherwise",
        ),
    ],
)
def test_not_a_mapping(text: str, message: str) -> None:
    assert only_problem(text) == f"demo.yaml:1:1: {message}"


def test_no_propositions() -> None:
    text = "name: x\npropositions: []\nphases: []\nclasses: []\notherwise: {id: u, answer: U}\n"
    assert (
        only_problem(text)
        == f"{where(text, '[]')}: propositions: a rule file needs at least one proposition"
    )


def test_missing_sections() -> None:
    assert problems("name: x\n") == [
        "demo.yaml:1:1: propositions: field required",
        "demo.yaml:1:1: phases: field required",
        "demo.yaml:1:1: classes: field required",
        "demo.yaml:1:1: otherwise: field required",
    ]


def test_many_problems_are_reported_together_in_file_order() -> None:
    text = edit("    text: Surface is plane\n", "    text: Surface is plane\n    colour: red\n")
    text = edit("  - B = ~C", "  - B = ~Q &", text)
    text = edit("propositions: [B, C]", "propositions: [B]", text)
    text = edit("    when: A & B", "    when: A & (B", text)
    text = edit("  id: unknown\n", "  id: 7\n", text)
    with pytest.raises(RuleFileError) as info:
        parse_rules(text, file="demo.yaml")
    lines = str(info.value).splitlines()
    assert lines == [
        f"{where(text, 'id: C', shift=4)}: propositions[2].id: proposition 'C' is in no phase",
        f"{where(text, 'colour')}: propositions[2].colour: unknown field",
        f"{where(text, 'Q &', shift=3)}: connections[0]: missing operand after '&': expected an id, a constant, '~' or '('",
        f"{where(text, '(B')}: classes[1].when: unbalanced '(': it is never closed",
        f"{where(text, '7')}: otherwise.id: an id must be a string, not the number 7 (quote it)",
    ]
    assert lines[2].endswith("missing operand after '&': expected an id, a constant, '~' or '('")
    n = at(text, "id: C")[0]
    w = len(str(n + 1))
    assert info.value.excerpt.splitlines() == [
        f"{n - 1:>{w}} |     feature: {{name: surface_curved, params: {{tolerance_deg: 20}}}}",
        f"{n:>{w}} |   - id: C",
        f"{'':>{w}} |         ^",
        f"{n + 1:>{w}} |     text: Surface is plane",
    ]


def test_malformed_expression_stops_only_that_expression() -> None:
    # a parse error in one place does not hide unknown ids in another
    text = edit("  - B = ~C", "  - B = ~C)")
    text = edit("    when: A & B", "    when: A & Zz", text)
    assert problems(text) == [
        f"{where(text, ')')}: connections[0]: unbalanced ')': no '(' to close",
        f"{where(text, 'Zz')}: classes[1].when: unknown proposition 'Zz'",
    ]


# --------------------------------------------------------------------------- finding files


def test_packaged_rule_sets_are_found() -> None:
    assert "parallelepipeds" in available_rule_sets()
    assert rules_directories()
    by_name = load_rules("parallelepipeds")
    assert by_name.name == "parallelepipeds"
    assert load_rules("parallelepipeds.yaml").ids == by_name.ids
    path = Path(by_name.file)
    assert path.name == "parallelepipeds.yaml"
    assert load_rules(path) == by_name
    assert load_rules(str(path)) == by_name


def test_a_file_path_is_loaded(tmp_path: Path) -> None:
    f = tmp_path / "mine.yaml"
    f.write_text(BASE, encoding="utf-8")
    assert load_rules(f).file == str(f)
    assert load_rules(str(f)).ids == ("A", "B", "C")
    bad = tmp_path / "bad.yaml"
    bad.write_text(BASE.replace("when: A & C", "when: A & Q"), encoding="utf-8")
    with pytest.raises(RuleFileError) as info:
        load_rules(str(bad))
    line, col = at(BASE, "A & C", shift=4)
    assert str(info.value) == f"{bad}:{line}:{col}: classes[0].when: unknown proposition 'Q'"


def test_unknown_name_names_the_packaged_sets() -> None:
    with pytest.raises(
        UsageError, match=r"no rule file 'cubes' .* packaged rule sets: .*parallelepipeds"
    ):
        load_rules("cubes")
    with pytest.raises(UsageError, match="packaged rule sets"):
        load_rules("nowhere/cubes.yaml")


def test_unreadable_path_is_a_rule_file_error(tmp_path: Path) -> None:
    with pytest.raises(RuleFileError, match="cannot read"):
        load_rules(tmp_path / "missing.yaml")


# --------------------------------------------------------------------------- the paper's base

PAPER = {
    "A": ("There is contact between the object and the finger", "I"),
    "B": ("Surface is curved", "II"),
    "C": ("Surface is plane", "II"),
    "D": ("Vertical edges are parallel", "III"),
    "E": ('"Vertical" edges join at one point', "III"),
    "F": ("Three pairs of parallel faces exist", "IV"),
    "G": ("Distances between neighbouring vertices are equal", "V"),
}


@pytest.fixture(scope="module")
def kb() -> RuleSet:
    return load_rules("parallelepipeds")


def test_paper_propositions_are_verbatim(kb: RuleSet) -> None:
    assert kb.ids[:7] == tuple(PAPER)
    for pid, (text, phase) in PAPER.items():
        assert (kb.proposition(pid).text, kb.proposition(pid).phase) == (text, phase)
    assert [p.id for p in kb.phases[:5]] == ["I", "II", "III", "IV", "V"]
    assert kb.connections[0].text == "B = A & ~C"


def test_feature_bindings_use_the_registry_names(kb: RuleSet) -> None:
    bindings = {p.id: (p.feature.name, p.feature.params) for p in kb.propositions if p.feature}
    assert bindings == {
        "A": ("contact", {}),
        "B": ("surface_curved", {}),
        "C": ("surface_plane", {}),
        "D": ("lateral_edges_parallel", {}),
        "E": ("lateral_edges_concurrent", {}),
        "F": ("parallel_face_pairs", {"count": 3}),
        "G": ("equal_edges", {}),
        "H": ("face_count", {"equals": 6}),
        "J": ("adjacent_faces_perpendicular", {}),
    }


# The truth values of real objects, resting on a face, worked out from their geometry (not from
# the rule file): A contact, B curved, C plane, D lateral edges parallel, E lateral edges meet at
# one point, F three pairs of parallel faces, G equal edges, H six faces, J adjacent faces
# perpendicular. F of the octahedron (four parallel pairs) is tried both ways.
OBJECTS = [
    ("cube", "1011011" + "11", "cube"),
    ("box 3x2x1", "1011010" + "11", "rectangular_parallelepiped"),
    ("box 2x2x1 (square base)", "1011010" + "11", "rectangular_parallelepiped"),
    ("oblique parallelepiped", "1011010" + "10", "nonrectangular_parallelepiped"),
    ("rhombohedron", "1011011" + "10", "nonrectangular_parallelepiped"),
    ("right prism on a rhombus", "1011010" + "10", "nonrectangular_parallelepiped"),
    ("regular tetrahedron", "1010101" + "00", "not_hexahedron"),
    ("irregular tetrahedron", "1010100" + "00", "not_hexahedron"),
    ("octahedron, F = at least three pairs", "1010011" + "00", "not_hexahedron"),
    ("octahedron, F = exactly three pairs", "1010001" + "00", "not_hexahedron"),
    ("square pyramid", "1010100" + "00", "not_hexahedron"),
    ("triangular prism", "1011000" + "00", "not_hexahedron"),
    ("hexagonal prism", "1011000" + "00", "not_hexahedron"),
    ("pentagonal pyramid", "1010100" + "10", "other_hexahedron"),
    ("square frustum", "1010100" + "10", "other_hexahedron"),
    ("triangular bipyramid", "1010000" + "10", "other_hexahedron"),
    ("sphere", "1100000" + "00", "not_hexahedron"),
    ("cylinder, envelope of six planes", "1101000" + "11", "not_hexahedron"),
    ("nothing touched", "0000000" + "00", "no_contact"),
]


@pytest.mark.parametrize(("label", "bits", "expected"), OBJECTS, ids=[o[0] for o in OBJECTS])
def test_every_object_gets_its_geometrically_right_class(
    kb: RuleSet, label: str, bits: str, expected: str
) -> None:
    values = {pid: bit == "1" for pid, bit in zip(kb.ids, bits, strict=True)}
    violated = [c.text for c in kb.connections if not evaluate(c.expr, values)]
    assert violated == [], label
    matched = [c.id for c in kb.classes if evaluate(c.expr, values)]
    assert matched == [expected], label


def test_fig5_answers(kb: RuleSet) -> None:
    answers = {c.id: c.answer for c in kb.classes}
    assert answers["cube"] == "OBJECT IS A CUBE"
    assert answers["rectangular_parallelepiped"] == "OBJECT IS A RECTANGULAR PARALLELEPIPED"
    assert answers["nonrectangular_parallelepiped"] == "OBJECT IS A NONRECTANGULAR PARALLELEPIPED"
    assert answers["not_hexahedron"] == "OBJECT IS NOT A HEXAHEDRON"


def test_classes_partition_the_reduced_disjunction(kb: RuleSet) -> None:
    members = 0
    for bits in itertools.product([False, True], repeat=len(kb.ids)):
        values = dict(zip(kb.ids, bits, strict=True))
        if all(evaluate(c.expr, values) for c in kb.connections):
            members += 1
            matched = [c.id for c in kb.classes if evaluate(c.expr, values)]
            assert len(matched) == 1, (values, matched)  # no gap, no overlap
    assert 0 < members < 2 ** len(kb.ids)


def test_cube_is_the_papers_single_conjunction_over_a_to_g(kb: RuleSet) -> None:
    # eq. (3): r(L) = A·B̄·C·D·Ē·F·G. The cube ∧ connections has exactly one model over the whole
    # enlarged base (so its minimal sum of products is that one full term), and its A–G part is
    # the paper's conjunction.
    cube = kb.rule_class("cube").expr
    models = []
    for bits in itertools.product([False, True], repeat=len(kb.ids)):
        values = dict(zip(kb.ids, bits, strict=True))
        if evaluate(cube, values) and all(evaluate(c.expr, values) for c in kb.connections):
            models.append("".join("1" if b else "0" for b in bits))
    assert models == ["1011011" + "11"]
    paper = parse_expr("A·B̄·C·D·Ē·F·G")
    assert paper == And(
        (Var("A"), Not(Var("B")), Var("C"), Var("D"), Not(Var("E")), Var("F"), Var("G"))
    )
    assert evaluate(
        paper,
        dict(zip(kb.ids, [True, False, True, True, False, True, True, True, True], strict=True)),
    )


# --------------------------------------------------------------------------- on real geometry


def _classify_mesh(
    kb: RuleSet, mesh: trimesh.Trimesh, *, quantise: bool
) -> tuple[str, list[str], list[str]]:
    from tactile_kb.features.builtin import get_feature
    from tactile_kb.geometry.model import build_model
    from tactile_kb.touch.finger import builtin_finger
    from tactile_kb.touch.synthetic import sample_record

    record = sample_record(mesh, builtin_finger("33"), per_face=12, seed=3, quantise=quantise)
    model = build_model(record)
    values = {}
    for p in kb.propositions:
        assert p.feature is not None
        values[p.id] = bool(get_feature(p.feature.name).fn(model, **p.feature.params))
    bits = "".join("1" if v else "0" for v in values.values())
    violated = [c.text for c in kb.connections if not evaluate(c.expr, values)]
    return bits, violated, [c.id for c in kb.classes if evaluate(c.expr, values)]


def test_packaged_feature_bindings_are_valid(kb: RuleSet) -> None:
    from tactile_kb.features.builtin import check_binding

    for p in kb.propositions:
        assert p.feature is not None
        assert check_binding(p.feature.name, p.feature.params) is None, p.id


@pytest.mark.parametrize("quantise", [False, True], ids=["exact", "33-sensor"])
def test_fig5_objects_get_the_papers_answers(kb: RuleSet, quantise: bool) -> None:
    from tactile_kb.solids import fig5_objects

    objects = fig5_objects()
    assert len(objects) == 12
    for name, mesh, label in objects:
        bits, violated, matched = _classify_mesh(kb, mesh, quantise=quantise)
        assert violated == [], (name, bits)
        assert matched == [label], (name, bits)


def test_other_solids_get_their_geometrically_right_class(kb: RuleSet) -> None:
    from tactile_kb import solids

    cases = [
        (solids.rhombohedron(0.07), "nonrectangular_parallelepiped"),
        (solids.rotate_about_z(solids.box(0.09, 0.05, 0.03), 0.7), "rectangular_parallelepiped"),
        (solids.pyramid(5, 0.05, 0.07), "other_hexahedron"),
        (solids.frustum(4, 0.06, 0.035, 0.05), "other_hexahedron"),
        (solids.prism(3, 0.05, 0.08), "not_hexahedron"),
        (solids.pyramid(4, 0.05, 0.06), "not_hexahedron"),
        (solids.cylinder(0.04, 0.08), "not_hexahedron"),
    ]
    for mesh, label in cases:
        bits, violated, matched = _classify_mesh(kb, mesh, quantise=True)
        assert violated == [], (label, bits)
        assert matched == [label], (label, bits)


def test_packaged_base_compiles_cleanly_with_the_papers_cube(kb: RuleSet) -> None:
    from tactile_kb.kb.compiler import compile_rules

    compiled = compile_rules(kb)
    assert compiled.problems == ()  # no dead class, overlap, gap or redundant connection
    assert (compiled.n, compiled.s_size, compiled.r_count) == (9, 512, 97)
    cube = next(c for c in compiled.classes if c.id == "cube")
    assert cube.paper == "A·B\u0304·C·D·E\u0304·F·G" + "·H·J"  # eq. (3), then the enlargement
    assert cube.bits == ("101101111",)


def test_duplicate_keys_are_reported_together_with_other_problems() -> None:
    text = edit("    text: Surface is plane\n", "    text: Surface is plane\n    text: again\n")
    text = edit("    when: A & B\n", "    when: A & Q\n", text)
    assert problems(text) == [
        f"{where(text, 'text: again')}: propositions[2].text: duplicate key 'text' (first at line "
        f"{at(text, 'text: Surface is plane')[0]})",
        f"{where(text, 'A & Q', shift=4)}: classes[1].when: unknown proposition 'Q'",
    ]
