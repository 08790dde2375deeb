"""Kinematics, no ROS: the model's legs compiled to straight-line code
(:class:`~a1_leg_fk.kinematics.quadruped.Quadruped`: positions, Jacobians, velocities, reach,
limits), the settings that build one (:mod:`~a1_leg_fk.kinematics.robot_config`) and inverse
kinematics (:mod:`a1_leg_fk.kinematics.ik`).
"""
