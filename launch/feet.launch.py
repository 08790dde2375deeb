"""Start the feet of a Unitree quadruped: ``ros2 launch a1_leg_fk feet.launch.py``.

Arguments: ``robot:=a1|go1|go2|b2|aliengo`` (the preset ``config/robots/<robot>.yaml``: which
joint-state input the robot's ROS driver gives), ``description:=FILE`` (a URDF: published by
robot_state_publisher on ``robot_description``, which the nodes follow; without it the nodes
follow whatever publishes ``robot_description``, else use the embedded A1),
``input:=joint_states|unitree_lowstate`` (overrides the preset's), ``odometry:=true|false``
(leg_odometry_node), ``rviz:=true|false`` (rviz2 with ``rviz/feet.rviz``, fixed frame the
robot's root link).

Checked statically by test/test_launch.py (the launch wheels are not on PyPI): every executable,
parameter and topic named here exists.
"""

from __future__ import annotations

import os

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchContext, LaunchDescription

PACKAGE = "a1_leg_fk"
FIXED_FRAMES = {"a1": "trunk", "go1": "base", "go2": "base", "b2": "base_link", "aliengo": "base"}
"""RViz's fixed frame per robot: the root link of its description (the embedded A1's for a1)."""
INPUTS = ("joint_states", "unitree_lowstate")
BOOLEANS = ("true", "false")


def generate_launch_description() -> LaunchDescription:
    """The launch arguments, and the nodes they choose."""
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "robot", default_value="a1", choices=list(FIXED_FRAMES), description="preset"
            ),
            DeclareLaunchArgument(
                "description", default_value="", description="URDF file ('': the topic)"
            ),
            DeclareLaunchArgument(
                "input",
                default_value="",
                choices=["", *INPUTS],
                description="joint states: joint_states or unitree_lowstate ('': the preset's)",
            ),
            DeclareLaunchArgument("odometry", default_value="true", choices=list(BOOLEANS)),
            DeclareLaunchArgument("rviz", default_value="true", choices=list(BOOLEANS)),
            OpaqueFunction(function=nodes),
        ]
    )


def nodes(context: LaunchContext) -> list[Node]:
    """foot_fk_node, and as the arguments ask: leg_odometry_node, robot_state_publisher, rviz2."""
    robot = LaunchConfiguration("robot").perform(context)
    description = LaunchConfiguration("description").perform(context)
    chosen_input = LaunchConfiguration("input").perform(context)
    share = get_package_share_directory(PACKAGE)
    preset = os.path.join(share, "config", "robots", f"{robot}.yaml")
    overrides = {"input": chosen_input} if chosen_input else {}
    started = [
        Node(
            package=PACKAGE,
            executable="foot_fk_node",
            parameters=[preset, overrides],
            output="screen",
        )
    ]
    if LaunchConfiguration("odometry").perform(context) == "true":
        started.append(
            Node(
                package=PACKAGE,
                executable="leg_odometry_node",
                parameters=[preset, overrides],
                output="screen",
            )
        )
    if description:
        with open(description, encoding="utf-8") as stream:
            text = stream.read()
        started.append(
            Node(
                package="robot_state_publisher",
                executable="robot_state_publisher",
                parameters=[{"robot_description": text}],
                output="screen",
            )
        )
    if LaunchConfiguration("rviz").perform(context) == "true":
        rviz = os.path.join(share, "rviz", "feet.rviz")
        started.append(
            Node(
                package="rviz2",
                executable="rviz2",
                arguments=["-d", rviz, "-f", FIXED_FRAMES[robot]],
                output="screen",
            )
        )
    return started
