"""S-expression reader/writer."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from protocol_helpers import MONITOR, PERCEPTS, UPSTREAM

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.sexpr import dumps, dumps_all, parse, parse_one, parse_spans


def test_basic_parse() -> None:
    assert parse("(a 1)(b (c d) ())") == [["a", "1"], ["b", ["c", "d"], []]]
    assert parse("") == []
    assert parse("  \n\t ") == []
    assert parse("atom") == ["atom"]
    assert parse_one(" (x) ") == ["x"]
    assert parse(b"(he1 0.5)(syn)") == [["he1", "0.5"], ["syn"]]


def test_whitespace_is_optional_around_parens_and_any_kind_separates() -> None:
    a = parse("(he1 0)(he2 0)(syn)")
    assert a == parse("(he1 0) (he2 0) (syn)") == parse("( he1\t0 )\n(he2\r\n0)\x0b(syn\x0c)")
    assert a == [["he1", "0"], ["he2", "0"], ["syn"]]


def test_quotes_and_odd_bytes_are_plain_atom_characters() -> None:
    assert parse('(say a"b\\c)') == [["say", 'a"b\\c']]
    # Latin-1 0xA0 and ASCII 0x1c are no whitespace for the C server; they stay inside the atom.
    assert parse(b"(say a\xa0b)") == [["say", "a\xa0b"]]
    assert parse("(say a\x1cb)") == [["say", "a\x1cb"]]


def test_fixture_percept_structure() -> None:
    exprs = parse(PERCEPTS[3])
    assert exprs[0] == ["time", ["now", "6.800"]]
    assert exprs[1][:5] == ["GS", ["sl", "0"], ["sr", "0"], ["t", "0.000"], ["pm", "BeforeKickOff"]]
    assert exprs[1][6] == ["ti", [["1", "penalty_none", "0.000"]], []]
    see = next(e for e in exprs if e[0] == "See")
    assert see[5] == ["B", ["pol", "1.084", "-4.739", "-28.260"]]
    assert sum(1 for e in exprs if e[0] == "HJ") == 22


@pytest.mark.parametrize(
    ("text", "offset", "what"),
    [
        ("(a (b)", 0, "unclosed"),
        ("(a)(b (c d)", 3, "unclosed"),
        ("(a))", 3, "unmatched"),
        (")(a)", 0, "unmatched"),
        ("(a)\n  )", 6, "unmatched"),
    ],
)
def test_structural_errors_name_the_offset(text: str, offset: int, what: str) -> None:
    with pytest.raises(ProtocolError, match=what) as info:
        parse(text)
    assert info.value.offset == offset
    assert f"offset {offset}" in str(info.value)


def test_truncated_messages_are_rejected_at_every_cut() -> None:
    for msg in (PERCEPTS[3], UPSTREAM):
        closes = {i + 1 for i, c in enumerate(msg) if c == ")"}
        for cut in range(1, len(msg)):
            prefix = msg[:cut]
            if prefix.count("(") == prefix.count(")") and cut in closes:
                assert parse(prefix)  # a complete prefix of whole predicates
                continue
            with pytest.raises(ProtocolError):
                parse(prefix)


def test_depth_guard() -> None:
    deep = "(" * 65 + ")" * 65
    with pytest.raises(ProtocolError, match="nesting deeper than 64") as info:
        parse(deep)
    assert info.value.offset == 64
    assert parse(deep, max_depth=100)[0] != []
    # Far beyond the recursion limit: still a clean error, no RecursionError, and no hang.
    with pytest.raises(ProtocolError):
        parse("(" * 200_000)
    assert len(parse("(a)" * 50_000)) == 50_000


def test_parse_spans_offsets() -> None:
    spans = parse_spans(" (a 1) b (c (d))")
    assert spans == [(1, ["a", "1"]), (7, "b"), (9, ["c", ["d"]])]
    assert [e for _, e in parse_spans(PERCEPTS[4])] == parse(PERCEPTS[4])
    with pytest.raises(ProtocolError):
        parse_spans("(a")


def test_dumps() -> None:
    assert dumps(["a", "1", ["b", []], 2, 0.5]) == "(a 1 (b ()) 2 0.5)"
    assert dumps("x") == "x"
    assert dumps_all([["he1", "0"], ["syn"]]) == "(he1 0)(syn)"
    for bad in (["a b"], [""], ["x)"], [None], [True]):
        with pytest.raises(ProtocolError):
            dumps(bad)  # type: ignore[arg-type]
    deep: list = []
    cur = deep
    for _ in range(5000):
        nxt: list = []
        cur.append(nxt)
        cur = nxt
    assert dumps(deep) == "(" * 5001 + ")" * 5001


def test_dumps_parse_round_trip_on_fixtures() -> None:
    for msg in [*PERCEPTS, UPSTREAM, MONITOR[3]]:
        exprs = parse(msg)
        assert parse(dumps_all(exprs)) == exprs
    # Upstream percepts are written exactly like this (no separators between predicates).
    assert dumps_all(parse(UPSTREAM)) == UPSTREAM


_atoms = st.text(
    alphabet=st.characters(min_codepoint=33, max_codepoint=126, blacklist_characters="()"),
    min_size=1,
    max_size=6,
)
_trees = st.recursive(_atoms, lambda kids: st.lists(kids, max_size=4), max_leaves=25)


@settings(max_examples=150, deadline=None)
@given(st.lists(_trees, max_size=4))
def test_round_trip_random_trees(exprs: list) -> None:
    text = dumps_all(exprs)
    assert parse(text) == [e for e in exprs]


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="() ab\t\n", max_size=40))
def test_random_text_parses_or_raises_protocol_error(text: str) -> None:
    try:
        result = parse(text, max_depth=8)
    except ProtocolError as exc:
        assert exc.offset is not None and 0 <= exc.offset <= len(text)
        return
    assert isinstance(result, list)
    assert text.count("(") == text.count(")")


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=120))
def test_random_bytes_parse_or_raise_protocol_error(data: bytes) -> None:
    try:
        result = parse(data)
    except ProtocolError as exc:
        assert exc.offset is not None
        return
    assert all(isinstance(e, str | list) for e in result)
