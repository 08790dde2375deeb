"""The console scripts of the package's ROS executables (setup.py's entry points).

Standard library only at import time. Each script enters :class:`StopSignals` first and only then
imports its node's module (rclpy, numpy, PyBullet: about 0.3 s), so a Ctrl-C/SIGTERM during those
imports sets the flag :func:`a1_leg_fk.ros.glue.run_node` shares (it then stops with exit 0)
instead of raising a KeyboardInterrupt traceback or killing the process.
"""

from __future__ import annotations

from a1_leg_fk.stop_signals import StopSignals


def foot_fk_node() -> int:
    """``ros2 run a1_leg_fk foot_fk_node``: :func:`a1_leg_fk.ros.foot_fk_node.main`."""
    with StopSignals():
        from a1_leg_fk.ros import foot_fk_node as node

        return node.main()


def foot_ik_node() -> int:
    """``ros2 run a1_leg_fk foot_ik_node``: :func:`a1_leg_fk.ros.foot_ik_node.main`."""
    with StopSignals():
        from a1_leg_fk.ros import foot_ik_node as ik_node

        return ik_node.main()


def joint_state_demo() -> int:
    """``ros2 run a1_leg_fk joint_state_demo``: :func:`a1_leg_fk.ros.joint_state_demo.main`."""
    with StopSignals():
        from a1_leg_fk.ros import joint_state_demo as demo

        return demo.main()


def leg_odometry_node() -> int:
    """``ros2 run a1_leg_fk leg_odometry_node``: :func:`a1_leg_fk.ros.leg_odometry_node.main`."""
    with StopSignals():
        from a1_leg_fk.ros import leg_odometry_node as node

        return node.main()
