"""Ctrl-C and SIGTERM as a flag instead of an exception, for the ``a1-leg-fk`` commands and the
nodes.

Imports only ``signal`` and ``threading`` (about 1 ms; ``typing`` alone costs 4): the executables
install it first, before their slow imports (rclpy, numpy, PyBullet).
"""

from __future__ import annotations

import signal
import threading

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (mypy knows the name)
if TYPE_CHECKING:
    from collections.abc import Callable
    from types import FrameType
    from typing import Any, Self

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopSignals:
    """Turns SIGINT and SIGTERM into a flag (``stop.is_set()``) instead of an exception.

    With rclpy's own signal handlers off, nothing is raised in the middle of a DDS call, of the
    cleanup or of an import (an exception raised at an arbitrary line can land in a library's
    ``except:`` or finalizer, which prints it and goes on); every loop that uses it waits in short
    slices and checks the flag. Entered inside another StopSignals (an executable's, installed
    before its imports), it shares that one's ``stop``: a signal that came before is not lost.
    Enter it in the main thread (Python's signal rule).

    Entering also unblocks both signals (restored on exit): a parent that starts the process with
    them blocked (``env --block-signal=INT,TERM ...``) covers the interpreter's own start-up,
    before any of our code runs; a signal sent then stays pending and is delivered here.
    """

    def __init__(self) -> None:
        self.stop = threading.Event()
        self.signal_name = ""
        self._previous: dict[int, Callable[[int, FrameType | None], Any] | int | None] = {}
        self._blocked: set[int] = set()

    def __enter__(self) -> Self:
        for number in STOP_SIGNALS:
            previous = signal.signal(number, self._handle)
            self._previous[number] = previous
            outer = getattr(previous, "__self__", None)
            if isinstance(outer, StopSignals):
                self.stop = outer.stop
        if hasattr(signal, "pthread_sigmask"):  # POSIX
            mask = signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)
            self._blocked = {number for number in STOP_SIGNALS if number in mask}
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self._blocked:
            signal.pthread_sigmask(signal.SIG_BLOCK, self._blocked)
        for number, handler in self._previous.items():
            signal.signal(number, handler)

    def _handle(self, number: int, _frame: object) -> None:
        self.signal_name = signal.Signals(number).name
        self.stop.set()
