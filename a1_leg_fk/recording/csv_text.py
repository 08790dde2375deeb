"""Numbers to CSV text fast: whole blocks of rows at once with numpy, instead of one Python
``repr`` per value (~1 µs each, which would dominate a long recording's conversion).

Floats are written with 17 significant digits, correctly rounded, in scientific notation with
trailing zeros dropped (``-2.9230713e-01``): 17 correctly rounded digits always give the same
binary64 back (``float(text) == value``). The decimal digits come from exact integer arithmetic:
``value * 10**k`` is computed exactly as a sum of two floats (Dekker's product), then rounded to
an integer. Values outside the fast path's range (zero, |x| < 1e-6 or >= 1e15, infinities) are
written with ``repr``; NaN is an empty cell. Integers are written in decimal.
"""

from __future__ import annotations

import numpy as np

CELL = 24  # bytes per value, before padding is removed; repr of any float fits
CHUNK_ROWS = 1024
"""Rows formatted at once: the numpy temporaries take about 150 bytes a value, so a block of a
smoothed window's 8,000 rows of 24 values at once would take some 30 MB for a moment (the
resident peak of ``odom``); in chunks, a few MB whatever the block's length."""
SPACE, COMMA, NEWLINE, ZERO = ord(" "), ord(","), ord("\n"), ord("0")
_SPLIT = 134217729.0  # 2**27 + 1, Veltkamp's splitting constant
_LOW, _HIGH = 1e-6, 1e15  # the fast path: 10**k is exact in binary64 for the k this range needs
_POWERS = 10.0 ** np.arange(0, 23)
_DIGITS = 17
_GROUP_TEXT = np.frombuffer(
    "".join(f"{n:04d}" for n in range(10_000)).encode(), dtype=np.uint32
)  # "0000".."9999"
_GROUP_ZEROS = np.array(
    [4 if n == 0 else len(str(n)) - len(str(n).rstrip("0")) for n in range(10_000)]
)
_PAIR_TEXT = np.frombuffer(
    "".join(f"{n:02d}" for n in range(100)).encode(), dtype=np.uint16
)  # "00".."99"
_COLUMNS = np.arange(_DIGITS - 1)


def _trailing_zeros(groups: np.ndarray) -> np.ndarray:
    """Trailing zero digits of the 16-digit numbers given as four 4-digit groups (N, 4)."""
    zeros = _GROUP_ZEROS.take(groups[:, 3])
    for group in (2, 1, 0):
        zeros += np.where(zeros == 4 * (3 - group), _GROUP_ZEROS.take(groups[:, group]), 0)
    return zeros


def format_rows(integers: np.ndarray, floats: np.ndarray) -> bytes:
    """CSV lines: the (R, I) int64 columns, then the (R, F) float64 columns; NaN -> empty cell."""
    rows = integers.shape[0]
    if rows > CHUNK_ROWS:
        return b"".join(
            format_rows(integers[start : start + CHUNK_ROWS], floats[start : start + CHUNK_ROWS])
            for start in range(0, rows, CHUNK_ROWS)
        )
    cells = np.full((rows, integers.shape[1] + floats.shape[1], CELL + 1), SPACE, dtype=np.uint8)
    cells[:, :, CELL] = COMMA
    cells[:, -1, CELL] = NEWLINE
    for column in range(integers.shape[1]):
        _put_integers(cells[:, column, :CELL], integers[:, column])
    float_cells = np.full((floats.size, CELL), SPACE, dtype=np.uint8)
    _put_floats(float_cells, floats.reshape(-1))
    cells[:, integers.shape[1] :, :CELL] = float_cells.reshape(rows, floats.shape[1], CELL)
    return cells.tobytes().translate(None, b" ")


def _put_integers(out: np.ndarray, values: np.ndarray) -> None:
    """Right-aligned decimal digits of non-negative int64 values (negative ones via ``str``)."""
    negative = values < 0
    remaining = np.where(negative, 0, values).astype(np.int64)
    for position in range(CELL - 1, CELL - 20, -1):
        remaining, digit = np.divmod(remaining, 10)
        out[:, position] = ZERO + digit
        if not remaining.any():
            break
    # leading zeros (all but the last digit) become padding
    head = out[:, :-1]
    leading = np.logical_and.accumulate((head == ZERO) | (head == SPACE), axis=1)
    out[:, :-1][leading] = SPACE
    for row in np.flatnonzero(negative):
        _put_text(out[row], str(int(values[row])))


def _put_floats(out: np.ndarray, values: np.ndarray) -> None:
    """Every lane is formatted as if in the fast range (others as 1.0), then the lanes outside
    it are overwritten: cheaper than selecting the fast lanes when nearly all are.
    """
    magnitude = np.abs(values)
    fast = (magnitude >= _LOW) & (magnitude < _HIGH)
    x = np.where(fast, magnitude, 1.0)
    exponent = np.floor(np.log10(x)).astype(np.int64)
    digits = _scaled(x, exponent)
    # log10 can be one off next to a power of ten: fix the exponent and scale again
    for _ in range(2):
        low, high = digits < 10 ** (_DIGITS - 1), digits >= 10**_DIGITS
        if not (low.any() or high.any()):
            break
        exponent = exponent - low + high
        digits = _scaled(x, exponent)
    out[:, 0] = np.where(values < 0, ord("-"), SPACE)
    first, rest = np.divmod(digits, 10 ** (_DIGITS - 1))
    out[:, 1] = ZERO + first
    out[:, 2] = ord(".")
    high, low = np.divmod(rest, 10**8)  # the 16 digits after the point as 4 groups of 4
    groups = np.empty((len(x), 4), dtype=np.intp)
    for half, column in ((high, 0), (low, 2)):
        half = half.astype(np.float64)  # < 10**8: exact, and so are these divisions' floors
        upper = np.floor(half / 10_000.0)
        groups[:, column], groups[:, column + 1] = upper, half - upper * 10_000.0
    fraction = _GROUP_TEXT.take(groups).view(np.uint8)
    keep = np.maximum(_DIGITS - 1 - _trailing_zeros(groups), 1)
    out[:, 3 : 3 + _DIGITS - 1] = np.where(keep[:, None] > _COLUMNS, fraction, SPACE)
    out[:, 19] = ord("e")
    out[:, 20] = np.where(exponent < 0, ord("-"), ord("+"))
    out[:, 21:23] = _PAIR_TEXT.take(np.abs(exponent)).view(np.uint8).reshape(-1, 2)
    if not fast.all():
        nan = np.isnan(values)
        out[nan] = SPACE
        for index in np.flatnonzero(~fast & ~nan):
            _put_text(out[index], repr(float(values[index])))


def _scaled(x: np.ndarray, exponent: np.ndarray) -> np.ndarray:
    """round(x * 10**(16 - exponent)) as int64, exactly (x in the fast range, so the power is an
    exactly representable 10**0 .. 10**22 and the product is >= 2**53, an integer float).
    """
    power = _POWERS[np.clip(_DIGITS - 1 - exponent, 0, len(_POWERS) - 1)]
    product = x * power
    x_split, p_split = _SPLIT * x, _SPLIT * power
    x_high = x_split - (x_split - x)
    x_low = x - x_high
    p_high = p_split - (p_split - power)
    p_low = power - p_high
    error = ((x_high * p_high - product) + x_high * p_low + x_low * p_high) + x_low * p_low
    scaled: np.ndarray = product.astype(np.int64) + np.rint(error).astype(np.int64)
    return scaled


def _put_text(out: np.ndarray, text: str) -> None:
    encoded = np.frombuffer(text.encode("ascii"), dtype=np.uint8)
    out[:] = SPACE
    out[: len(encoded)] = encoded
