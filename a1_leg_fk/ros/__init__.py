"""The ROS 2 glue, the only package besides :mod:`a1_leg_fk.cli` that imports rclpy: the nodes
(foot_fk_node, foot_ik_node, joint_state_demo), their robot source, diagnostics, markers and
pre-serialized output, and the console scripts (:mod:`~a1_leg_fk.ros.executables`).

Importing this package imports nothing: each executable imports its node only after installing
the stop-signal flag.
"""
