"""The model corrections a node runs with, from its ``model_corrections`` and
``model_corrections_file`` parameters (``foot_fk_node`` and ``leg_odometry_node`` alike): a
calibration's file (``a1-leg-fk calibrate``) that does not match the robot, or cannot be read, is
refused in one logged line naming the file and the reason, and the node runs on the nominal model
(no corrections), the refusal in its /diagnostics.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from rclpy.node import Node

from a1_leg_fk.estimation.correction_file import CorrectionFileError
from a1_leg_fk.estimation.model_corrections import OFF

FILE = "file"
"""``model_corrections: file``: the terms of ``model_corrections_file``, as they are."""
Built = TypeVar("Built")


def corrections_mode(mode: str, path: str) -> str:
    """What the estimators get from ``mode`` (online, off or file) and ``path`` (the file
    parameter, "" none): the file's path when ``mode`` is file, or online with a file given (the
    file wins over learning); else ``mode``. :class:`CorrectionFileError` for file without a path.
    """
    if mode == FILE and not path:
        raise CorrectionFileError("model_corrections 'file' without a model_corrections_file")
    return path if path and mode != OFF else mode


def with_corrections(node: Node, build: Callable[[str], Built]) -> tuple[Built, str]:
    """``build`` (an estimator of ``model_corrections``: online, off or a file's path) with the
    node's choice, and "" ; or, when the file is refused, ``build(OFF)`` and the reason (logged as
    one error line). Other errors of ``build`` are the caller's.
    """
    mode = str(node.get_parameter("model_corrections").value)
    path = str(node.get_parameter("model_corrections_file").value)
    try:
        return build(corrections_mode(mode, path)), ""
    except CorrectionFileError as error:
        refusal = str(error)
    node.get_logger().error(f"{refusal}: refused, running on the nominal model (no corrections)")
    return build(OFF), refusal
