"""C-compatible number conversion and formatting."""

from __future__ import annotations

import math

import pytest

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.values import (
    atof,
    atoi,
    fmt_fixed,
    fmt_g,
    fmt_short,
    is_atom,
    strict_float,
    strict_int,
)


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1.5", 1.5),
        ("-0.25", -0.25),
        ("3", 3.0),
        ("1.5abc", 1.5),
        ("abc", 0.0),
        ("", 0.0),
        ("-", 0.0),
        (".5", 0.5),
        ("5.", 5.0),
        ("1e3", 1000.0),
        ("1e", 1.0),
        ("1e+", 1.0),
        ("+2", 2.0),
        ("0x10", 16.0),
        ("0x1p-1", 0.5),
        ("0x", 0.0),
        ("inf", math.inf),
        ("-Infinity", -math.inf),
        ("1e400", math.inf),
    ],
)
def test_atof_like_c(text: str, value: float) -> None:
    assert atof(text) == value


def test_atof_nan_and_negative_zero() -> None:
    assert math.isnan(atof("nan"))
    assert math.isnan(atof("-NaN(123)"))
    assert math.copysign(1.0, atof("-0.00")) == -1.0


def test_atoi() -> None:
    assert atoi("7") == 7
    assert atoi("3.7") == 3
    assert atoi("-3.7") == -3
    assert atoi("x") == 0
    assert atoi("nan") == 0
    assert atoi("inf") == 0


def test_strict() -> None:
    assert strict_float("-0.000") == 0.0
    assert math.isnan(strict_float("nan"))
    assert strict_int("3") == 3
    assert strict_int("3.0") == 3
    for bad in ("abc", "1.5x", "", "1_0", "1e"):
        with pytest.raises(ProtocolError):
            strict_float(bad)
    for bad in ("3.5", "x", "nan"):
        with pytest.raises(ProtocolError):
            strict_int(bad)


def test_formatting() -> None:
    assert fmt_fixed(-0.001) == "-0.00"
    assert fmt_fixed(9.8123) == "9.81"
    assert fmt_fixed(1.005, 3) == "1.005"
    assert fmt_fixed(math.nan) == "nan"
    assert fmt_g(30) == "30"
    assert fmt_g(0.042) == "0.042"
    assert fmt_g(-8.742278e-08) == "-8.74228e-08"
    assert fmt_g(-0.0) == "-0"
    assert fmt_g(0.0402764123) == "0.0402764"
    assert fmt_short(-1.0) == "-1"
    assert fmt_short(0.5) == "0.5"
    assert fmt_short(-0.0) == "-0"
    assert fmt_short(1e-5) == "1e-05"
    assert fmt_short(math.inf) == "inf"
    for v in (0.1, -14.5, 1 / 3, 1e-300, 123456789.123):
        assert atof(fmt_short(v)) == v


def test_is_atom() -> None:
    assert is_atom("Hi!")
    assert not is_atom("")
    assert not is_atom("a b")
    assert not is_atom("a(")
    assert not is_atom(3)
