"""The console scripts of the package's ROS executables (setup.py's entry points).

Standard library only at import time (``signal`` and ``threading``). Each script enters
:class:`StopSignals` first and only then imports its node's module (rclpy, numpy, PyBullet: about
0.3 s). A Ctrl-C/SIGTERM from then on sets the flag :func:`a1_leg_fk.ros.glue.run_node` shares:
one during the imports lets them finish and ends with exit 0 before anything is started (no
exception is raised into the imports: library code would catch and print it), one after them
stops the node with exit 0. What comes before the script's first line is the interpreter's own
start-up (see :class:`StopSignals` for a parent that blocks the signals over it).
"""

from __future__ import annotations

from a1_leg_fk.stop_signals import StopSignals


def _run(module: str) -> int:
    """Import ``module`` under a :class:`StopSignals` and run its ``main()``, whose
    :func:`~a1_leg_fk.ros.glue.run_node` returns 0 before starting anything if a signal came
    meanwhile.
    """
    with StopSignals():  # a signal pending since the exec arrives here: the flag
        return int(__import__(module, fromlist=["main"]).main())


def foot_fk_node() -> int:
    """``ros2 run a1_leg_fk foot_fk_node``: :func:`a1_leg_fk.ros.foot_fk_node.main`."""
    return _run("a1_leg_fk.ros.foot_fk_node")


def foot_ik_node() -> int:
    """``ros2 run a1_leg_fk foot_ik_node``: :func:`a1_leg_fk.ros.foot_ik_node.main`."""
    return _run("a1_leg_fk.ros.foot_ik_node")


def joint_state_demo() -> int:
    """``ros2 run a1_leg_fk joint_state_demo``: :func:`a1_leg_fk.ros.joint_state_demo.main`."""
    return _run("a1_leg_fk.ros.joint_state_demo")


def leg_odometry_node() -> int:
    """``ros2 run a1_leg_fk leg_odometry_node``: :func:`a1_leg_fk.ros.leg_odometry_node.main`."""
    return _run("a1_leg_fk.ros.leg_odometry_node")
