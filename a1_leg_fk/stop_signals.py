"""Ctrl-C and SIGTERM as a flag instead of an exception, for the ``a1-leg-fk`` commands and the
nodes.

Standard library only: the executables install it before their slow imports (rclpy, numpy,
PyBullet).
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from types import FrameType
from typing import Any, Self

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopSignals:
    """Turns SIGINT and SIGTERM into a flag (``stop.is_set()``) instead of an exception.

    With rclpy's own signal handlers off, nothing is raised in the middle of a DDS call or of the
    cleanup; every loop that uses it waits in short slices and checks the flag. Entered inside
    another StopSignals (an executable's, installed before its imports), it shares that one's
    ``stop``: a signal that came before is not lost. Enter it in the main thread (Python's signal
    rule).
    """

    def __init__(self) -> None:
        self.stop = threading.Event()
        self.signal_name = ""
        self._previous: dict[int, Callable[[int, FrameType | None], Any] | int | None] = {}

    def __enter__(self) -> Self:
        for number in STOP_SIGNALS:
            previous = signal.signal(number, self._handle)
            self._previous[number] = previous
            outer = getattr(previous, "__self__", None)
            if isinstance(outer, StopSignals):
                self.stop = outer.stop
        return self

    def __exit__(self, *exc_info: object) -> None:
        for number, handler in self._previous.items():
            signal.signal(number, handler)

    def _handle(self, number: int, _frame: object) -> None:
        self.signal_name = signal.Signals(number).name
        self.stop.set()
