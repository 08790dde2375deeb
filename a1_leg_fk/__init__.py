"""The feet of a quadruped from its URDF: forward and inverse kinematics, recordings, gaits, and
ROS 2 nodes around them.

The public API, importable from here without ROS::

    from a1_leg_fk import Quadruped
    robot = Quadruped.from_urdf()            # the embedded Unitree A1
    feet = robot.fk([0.0, 0.8, -1.5] * 4)    # (4, 3) metres, FR FL RR RL, base frame

The names are re-exported lazily (PEP 562): ``import a1_leg_fk`` costs nothing, so the console
scripts in :mod:`a1_leg_fk.ros.executables` can catch Ctrl-C before any heavy import. The layout:
:mod:`~a1_leg_fk.model` (URDF, legs) <- :mod:`~a1_leg_fk.kinematics` (FK, IK) <-
:mod:`~a1_leg_fk.tracking` (JointState rules) <- :mod:`~a1_leg_fk.recording`,
:mod:`~a1_leg_fk.gait`, :mod:`~a1_leg_fk.verify`, :mod:`~a1_leg_fk.plots` <- :mod:`~a1_leg_fk.ros`
(the only rclpy user besides :mod:`~a1_leg_fk.cli`).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
    from a1_leg_fk.estimation.momentum_observer import MomentumObserver
    from a1_leg_fk.gait.analysis import GaitReport, analyze_gait
    from a1_leg_fk.kinematics.quadruped import Quadruped
    from a1_leg_fk.kinematics.robot_config import RobotConfig, load_robot
    from a1_leg_fk.model.legs import LEG_NAMES
    from a1_leg_fk.model.urdf import LegFkError, RobotModel, load_urdf
    from a1_leg_fk.recording.trajectories import FootTrajectories, read_foot_trajectories

_HOMES = {
    "LEG_NAMES": "a1_leg_fk.model.legs",
    "LegFkError": "a1_leg_fk.model.urdf",
    "RobotModel": "a1_leg_fk.model.urdf",
    "load_urdf": "a1_leg_fk.model.urdf",
    "Quadruped": "a1_leg_fk.kinematics.quadruped",
    "RobotConfig": "a1_leg_fk.kinematics.robot_config",
    "load_robot": "a1_leg_fk.kinematics.robot_config",
    "FootTrajectories": "a1_leg_fk.recording.trajectories",
    "read_foot_trajectories": "a1_leg_fk.recording.trajectories",
    "GaitReport": "a1_leg_fk.gait.analysis",
    "analyze_gait": "a1_leg_fk.gait.analysis",
    "MomentumObserver": "a1_leg_fk.estimation.momentum_observer",
    "ContactEstimator": "a1_leg_fk.estimation.contact_estimator",
    "ImuSample": "a1_leg_fk.estimation.contact_estimator",
}
"""Each public name and the module that defines it."""

__all__ = [
    "LEG_NAMES",
    "ContactEstimator",
    "FootTrajectories",
    "GaitReport",
    "ImuSample",
    "LegFkError",
    "MomentumObserver",
    "Quadruped",
    "RobotConfig",
    "RobotModel",
    "analyze_gait",
    "load_robot",
    "load_urdf",
    "read_foot_trajectories",
]


def __getattr__(name: str) -> Any:
    """The public name ``name``, imported from its module on first use."""
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'a1_leg_fk' has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
