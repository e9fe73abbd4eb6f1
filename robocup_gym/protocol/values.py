"""Number conversion and formatting exactly as the C/C++ server does it.

* :func:`atof` / :func:`atoi`: the lenient conversions the server applies to numbers sent by
  agents (C ``atof``: the longest numeric prefix, anything else is 0).
* :func:`strict_float` / :func:`strict_int`: conversions for data that must be numeric
  (percepts, trainer commands); they raise :class:`~robocup_gym.protocol.errors.ProtocolError`.
* :func:`fmt_fixed`: ``printf("%.2f")`` (percepts); :func:`fmt_g`: C++ default stream
  formatting, ``printf("%g")`` (monitor stream); :func:`fmt_short`: the shortest text that reads
  back to the same float (commands).
"""

from __future__ import annotations

import math
import re

from robocup_gym.protocol.errors import ProtocolError

__all__ = [
    "atof",
    "atoi",
    "fmt_fixed",
    "fmt_g",
    "fmt_short",
    "is_atom",
    "strict_float",
    "strict_int",
]

# The prefix that C strtod/atof accepts: decimal or hexadecimal floats, inf/infinity, nan[(…)].
_ATOF_PREFIX = re.compile(
    r"[ \t\n\r\v\f]*"
    r"([+-]?(?:"
    r"0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)(?:[pP][+-]?[0-9]+)?"
    r"|(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
    r"|[iI][nN][fF](?:[iI][nN][iI][tT][yY])?"
    r"|[nN][aA][nN](?:\([0-9A-Za-z_]*\))?"
    r"))"
)
_STRICT_INT = re.compile(r"[+-]?[0-9]+")
_ATOM_BAD = re.compile(r"[\s()]")


def atof(text: str) -> float:
    """C ``atof``: the longest numeric prefix of ``text`` as a float; 0.0 if there is none.

    ``"1.5abc"`` → 1.5, ``"abc"`` → 0.0, ``"nan"`` → nan, ``"-inf"`` → -inf, ``"1e400"`` → inf.
    """
    m = _ATOF_PREFIX.match(text)
    if m is None:
        return 0.0
    num = m.group(1)
    body = num.lstrip("+-")
    if body[:2] in ("0x", "0X"):
        try:
            return float.fromhex(num)
        except OverflowError:
            return -math.inf if num.startswith("-") else math.inf
    low = body.lower()
    if low.startswith("nan"):
        return math.nan
    if low.startswith("inf"):
        return -math.inf if num.startswith("-") else math.inf
    return float(num)


def atoi(text: str) -> int:
    """An integer parameter as the server reads it: ``int(atof(text))`` truncated towards zero.

    ``"3"`` → 3, ``"3.7"`` → 3, ``"x"`` → 0; nan and ±inf give 0.
    """
    value = atof(text)
    if not math.isfinite(value):
        return 0
    return int(value)


def strict_float(text: str, *, predicate: str | None = None) -> float:
    """``text`` as a float; ``nan``/``inf`` are accepted, anything non-numeric raises.

    Raises:
        ProtocolError: when ``text`` is not a number (or is not an atom).
    """
    if isinstance(text, str) and _ATOF_PREFIX.fullmatch(text) is not None:
        return atof(text)
    raise ProtocolError(f"expected a number, got {text!r}", predicate=predicate)


def strict_int(text: str, *, predicate: str | None = None) -> int:
    """``text`` as an integer; an integral float written like ``3.0`` is accepted.

    Raises:
        ProtocolError: when ``text`` is not an integer.
    """
    if isinstance(text, str):
        if _STRICT_INT.fullmatch(text) is not None:
            return int(text)
        if _ATOF_PREFIX.fullmatch(text) is not None:
            value = atof(text)
            if math.isfinite(value) and value == int(value):
                return int(value)
    raise ProtocolError(f"expected an integer, got {text!r}", predicate=predicate)


def fmt_fixed(value: float, decimals: int = 2) -> str:
    """``printf("%.<decimals>f")``: ``0.00``, ``-0.00``, ``9.81``, ``nan``, ``inf``."""
    if value != value:  # nan (glibc prints "-nan" for a negative nan; we always print "nan")
        return "nan"
    return f"{value:.{decimals}f}"


def fmt_g(value: float) -> str:
    """C++ default stream formatting (``printf("%g")``, 6 significant digits).

    ``30`` → ``30``, ``0.042`` → ``0.042``, ``-8.742278e-08`` → ``-8.74228e-08``, ``-0.0`` → ``-0``.
    """
    if isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    return f"{value:g}"


def fmt_short(value: float) -> str:
    """The shortest text that reads back to the same float, integers without ``.0``.

    ``-1.0`` → ``-1``, ``0.5`` → ``0.5``, ``1e-05`` → ``1e-05``.
    """
    value = float(value)
    if value != value:
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if value == int(value) and abs(value) < 1e16:
        text = str(int(value))
        return "-0" if text == "0" and math.copysign(1.0, value) < 0 else text
    return repr(value)


def is_atom(text: object) -> bool:
    """True if ``text`` is a non-empty string without whitespace and parentheses."""
    return isinstance(text, str) and bool(text) and _ATOM_BAD.search(text) is None
