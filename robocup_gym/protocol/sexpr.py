"""S-expression reader and writer for the rcssserver3d wire format (wire reference §1.5).

Atoms are strings (numbers stay text; convert them with :mod:`robocup_gym.protocol.values`),
lists are Python lists. Whitespace (space, tab, newline, CR, VT, FF) separates atoms and is
optional around parentheses. Double quotes have no special meaning (the server never emits
quoted atoms, and ``"`` is a legal character of ``say`` messages).

The reader is iterative (no recursion), bounds the nesting depth and reports unbalanced or
truncated input as :class:`~robocup_gym.protocol.errors.ProtocolError` with the offset.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Union

from robocup_gym.protocol.errors import ProtocolError

__all__ = [
    "DEFAULT_MAX_DEPTH",
    "SExpr",
    "dumps",
    "dumps_all",
    "parse",
    "parse_one",
    "parse_spans",
]

SExpr = Union[str, list["SExpr"]]  # noqa: UP007 - recursive alias must stay a runtime Union
"""An atom (``str``) or a list of S-expressions."""

DEFAULT_MAX_DEPTH = 64
"""Deepest accepted nesting (percepts need 4, monitor scene graphs ~10)."""

# ASCII characters that str.split() treats as whitespace but C isspace() does not.
_ODD_SPACE = re.compile("[\x1c-\x1f]")
_TOKEN = re.compile(r"\(|\)|[^ \t\n\r\v\f()]+")
_ATOM_BAD = re.compile(r"[ \t\n\r\v\f()]")


def parse(text: str | bytes | bytearray, *, max_depth: int = DEFAULT_MAX_DEPTH) -> list[SExpr]:
    """All top-level expressions of ``text``, in order.

    ``"(a 1)(b (c))"`` → ``[["a", "1"], ["b", ["c"]]]``; a top-level atom is returned as a
    ``str`` element; empty or blank text gives ``[]``. Bytes are decoded as Latin-1.

    Raises:
        ProtocolError: for an unmatched ``)``, an unclosed ``(`` (truncated input) or nesting
            deeper than ``max_depth``; the message names the offset.
    """
    if not isinstance(text, str):
        text = bytes(text).decode("latin-1")
    if text.isascii() and (text.isprintable() or _ODD_SPACE.search(text) is None):
        tokens = text.replace("(", " ( ").replace(")", " ) ").split()
    else:
        tokens = _TOKEN.findall(text)
    stack: list[list[SExpr]] = []
    push = stack.append
    pop = stack.pop
    cur: list[SExpr] = []
    for tok in tokens:
        if tok == "(":
            new: list[SExpr] = []
            cur.append(new)
            push(cur)
            cur = new
            if len(stack) > max_depth:
                _raise_located(text, max_depth)
        elif tok == ")":
            if not stack:
                _raise_located(text, max_depth)
            cur = pop()
        else:
            cur.append(tok)
    if stack:
        _raise_located(text, max_depth)
    return cur


def parse_one(text: str | bytes | bytearray, *, max_depth: int = DEFAULT_MAX_DEPTH) -> SExpr:
    """Exactly one expression (surrounding whitespace allowed).

    Raises:
        ProtocolError: for malformed input, no expression, or more than one.
    """
    exprs = parse(text, max_depth=max_depth)
    if len(exprs) != 1:
        raise ProtocolError(f"expected exactly one S-expression, found {len(exprs)}")
    return exprs[0]


def parse_spans(
    text: str | bytes | bytearray, *, max_depth: int = DEFAULT_MAX_DEPTH
) -> list[tuple[int, SExpr]]:
    """Like :func:`parse`, but each top-level expression comes with its start offset.

    Slower than :func:`parse`; meant for error reporting and tools.

    Raises:
        ProtocolError: as :func:`parse`.
    """
    if not isinstance(text, str):
        text = bytes(text).decode("latin-1")
    result: list[tuple[int, SExpr]] = []
    stack: list[list[SExpr]] = []
    cur: list[SExpr] = []
    for m in _TOKEN.finditer(text):
        tok = m.group()
        if tok == "(":
            new: list[SExpr] = []
            if not stack:
                result.append((m.start(), new))
            else:
                cur.append(new)
            stack.append(cur)
            cur = new
            if len(stack) > max_depth:
                _raise_located(text, max_depth)
        elif tok == ")":
            if not stack:
                _raise_located(text, max_depth)
            cur = stack.pop()
        elif not stack:
            result.append((m.start(), tok))
        else:
            cur.append(tok)
    if stack:
        _raise_located(text, max_depth)
    return result


def _raise_located(text: str, max_depth: int) -> None:
    """Find the first structural error in ``text`` (slow, with offsets) and raise it."""
    opened: list[int] = []
    for m in _TOKEN.finditer(text):
        tok = m.group()
        if tok == "(":
            opened.append(m.start())
            if len(opened) > max_depth:
                raise ProtocolError(
                    f"nesting deeper than {max_depth} levels", offset=m.start(), text=text
                )
        elif tok == ")":
            if not opened:
                raise ProtocolError("unmatched ')'", offset=m.start(), text=text)
            opened.pop()
    if opened:
        raise ProtocolError(
            f"unclosed '(' (input truncated? {len(opened)} list(s) still open at the end)",
            offset=opened[-1],
            text=text,
        )
    raise ProtocolError("malformed S-expression")  # pragma: no cover - parse() found an error


def dumps(expr: SExpr | int | float) -> str:
    """``expr`` as text: ``["a", "1", ["b"]]`` → ``"(a 1 (b))"``.

    Atoms may be ``str``, ``int`` or ``float`` (written with ``str()``; format numbers yourself
    when the exact notation matters). Iterative, so deep nesting is fine.

    Raises:
        ProtocolError: for an atom that is empty or contains whitespace or parentheses, or an
            element of an unsupported type.
    """
    if not isinstance(expr, list):
        return _atom_text(expr)
    out: list[str] = []
    # Each stack entry: (list, index of the next element).
    stack: list[tuple[list[SExpr], int]] = [(expr, 0)]
    out.append("(")
    while stack:
        lst, i = stack.pop()
        if i < len(lst):
            item = lst[i]
            stack.append((lst, i + 1))
            if i:
                out.append(" ")
            if isinstance(item, list):
                out.append("(")
                stack.append((item, 0))
            else:
                out.append(_atom_text(item))
        else:
            out.append(")")
    return "".join(out)


def dumps_all(exprs: Iterable[SExpr]) -> str:
    """Several expressions back to back without separators, as the server writes percepts.

    Two top-level atoms in a row are separated by one space (they would merge otherwise).
    """
    out: list[str] = []
    prev_atom = False
    for e in exprs:
        atom = not isinstance(e, list)
        if atom and prev_atom:
            out.append(" ")
        out.append(dumps(e))
        prev_atom = atom
    return "".join(out)


def _atom_text(atom: object) -> str:
    if isinstance(atom, bool):
        raise ProtocolError(f"cannot write {atom!r} as an S-expression atom")
    if isinstance(atom, str):
        text = atom
    elif isinstance(atom, int | float):
        text = str(atom)
    else:
        raise ProtocolError(f"cannot write {type(atom).__name__} {atom!r} as an S-expression atom")
    if not text or _ATOM_BAD.search(text) is not None:
        raise ProtocolError(f"invalid atom {text!r}: must be non-empty, without spaces or parens")
    return text
