"""csv_text.format_rows: every float comes back bit for bit through float(text); NaN is empty."""

from __future__ import annotations

import math
import struct

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from a1_leg_fk.recording.csv_text import format_rows


def cells_back(text: bytes, columns: int) -> list[list[str]]:
    lines = text.decode("ascii").split("\n")
    assert lines[-1] == ""
    rows = [line.split(",") for line in lines[:-1]]
    assert all(len(row) == columns for row in rows)
    return rows


def same_bits(a: float, b: float) -> bool:
    return struct.pack("<d", a) == struct.pack("<d", b)


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=1, max_size=40),
    st.lists(st.integers(-(2**63), 2**63 - 1), min_size=2, max_size=2),
)
def test_any_float_round_trips(values: list[float], integers: list[int]) -> None:
    floats = np.array(values).reshape(-1, 1)
    ints = np.array([integers] * len(values), dtype=np.int64)
    for row, value in zip(cells_back(format_rows(ints, floats), 3), values):
        assert [int(cell) for cell in row[:2]] == integers
        if math.isnan(value):
            assert row[2] == ""
        else:
            assert same_bits(float(row[2]), value), (row[2], repr(value))


def test_many_random_bit_patterns_and_foot_like_values() -> None:
    rng = np.random.default_rng(2)
    values = np.concatenate(
        [
            rng.integers(0, 2**64, size=60_000, dtype=np.uint64).view(np.float64),
            rng.normal(size=60_000) * 0.3,
            rng.uniform(-1, 1, 6_000) * 10.0 ** rng.integers(-8, 17, 6_000),
            [
                1e-6,
                -1e-6,
                1e15,
                -1e15,
                9.999999999999999e14,
                0.1,
                0.3,
                1 / 3,
                2.0**-20,
                0.0,
                -0.0,
                5e-324,
            ],
        ]
    )
    values = values[: len(values) // 6 * 6].reshape(-1, 6)
    stamps = np.stack(
        [
            np.arange(len(values), dtype=np.int64) * 999_999_937,
            np.full(len(values), 1_700_000_000_123_456_789),
        ],
        axis=1,
    )
    rows = cells_back(format_rows(stamps, values), 8)
    got = np.array([[float(cell) if cell else math.nan for cell in row[2:]] for row in rows])
    finite = ~np.isnan(values)
    assert (got[finite].view(np.int64) == values[finite].view(np.int64)).all()
    assert np.isnan(got[~finite]).all()
    assert [int(row[0]) for row in rows] == stamps[:, 0].tolist() and {row[1] for row in rows} == {
        "1700000000123456789"
    }


def seventeen_digits(value: float) -> str:
    """Python's correctly rounded 17 significant digits, trailing zeros of the fraction dropped."""
    mantissa, exponent = f"{value:.16e}".split("e")
    mantissa = mantissa.rstrip("0")
    return f"{mantissa}0e{exponent}" if mantissa.endswith(".") else f"{mantissa}e{exponent}"


def test_text_is_the_correctly_rounded_17_digits() -> None:
    rng = np.random.default_rng(4)
    values = np.concatenate(
        [
            rng.normal(size=3000) * 0.3,
            rng.uniform(-1, 1, 3000) * 10.0 ** rng.integers(-6, 15, 3000),
            [0.25, -0.5, 1.0],
        ]
    )
    rows = cells_back(
        format_rows(np.zeros((len(values), 2), dtype=np.int64), values.reshape(-1, 1)), 3
    )
    for row, value in zip(rows, values):  # outside 1e-6 <= |x| < 1e15 the text is repr's
        assert row[2] == (
            seventeen_digits(value) if 1e-6 <= abs(value) < 1e15 else repr(float(value))
        )
    special = format_rows(
        np.array([[5, 0]], dtype=np.int64), np.array([[0.25, math.nan, 0.0, -0.0, 1e-9, math.inf]])
    )
    assert special == b"5,0,2.5e-01,,0.0,-0.0,1e-09,inf\n"
