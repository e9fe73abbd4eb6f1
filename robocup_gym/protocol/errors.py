"""The one exception type of the protocol package."""

from __future__ import annotations

__all__ = ["ProtocolError"]


class ProtocolError(ValueError):
    """Malformed or unsupported data on the wire.

    The message says what is wrong and where; the same facts are kept as attributes so callers
    can react programmatically.

    Attributes:
        offset: character offset in the message (equal to the byte offset: messages are decoded
            as Latin-1, one byte per character), or ``None`` when no position applies.
        predicate: name of the predicate concerned (``"HJ"``, ``"beam"``, …), or ``None``.
    """

    def __init__(
        self,
        message: str,
        *,
        offset: int | None = None,
        predicate: str | None = None,
        text: str | None = None,
    ) -> None:
        self.offset = offset
        self.predicate = predicate
        where = []
        if predicate is not None:
            where.append(f"in predicate {predicate!r}")
        if offset is not None:
            where.append(f"at offset {offset}")
        full = message
        if where:
            full = f"{message} ({', '.join(where)})"
        if text is not None and offset is not None:
            full = f"{full}: {_context(text, offset)}"
        super().__init__(full)


def _context(text: str, offset: int, width: int = 24) -> str:
    """A short excerpt of ``text`` around ``offset`` with a ``⟨here⟩`` marker."""
    start = max(0, offset - width)
    end = min(len(text), offset + width)
    before = ("…" if start > 0 else "") + text[start:offset]
    after = text[offset:end] + ("…" if end < len(text) else "")
    return repr(before + "⟨here⟩" + after)
