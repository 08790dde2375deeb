"""Publishes Unitree LowState messages on ``lowstate`` (50 Hz) until stopped, with the user's
message class (``unitree_go.msg.LowState``, built by the test): motors 0-11 at the A1's standing
pose (:data:`shared.STANDING`, FR, FL, RR, RL x hip, thigh, calf), the IMU level (quaternion w
first: 1, 0, 0, 0), at rest. Run by test/ros/test_lowstate_node.py with the install's environment.
"""

from __future__ import annotations

import contextlib

import rclpy
from shared import STANDING
from unitree_go.msg import LowState  # type: ignore[import-not-found]  # built by the test


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("lowstate_publisher")
    publisher = node.create_publisher(LowState, "lowstate", 10)
    message = LowState()
    for index, angle in enumerate(STANDING):
        message.motor_state[index].q = float(angle)
    message.imu_state.quaternion[0] = 1.0
    message.imu_state.accelerometer[2] = 9.81

    def publish() -> None:
        message.tick += 20
        publisher.publish(message)

    node.create_timer(0.02, publish)
    with contextlib.suppress(KeyboardInterrupt):
        rclpy.spin(node)


if __name__ == "__main__":
    main()
