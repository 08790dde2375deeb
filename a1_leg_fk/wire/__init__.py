"""Decoders of the serialized messages the package reads (ROS 2 CDR and ROS 1), used by the live
nodes (raw subscriptions) and the bag tools alike: ``sensor_msgs/msg/JointState``
(:mod:`~a1_leg_fk.wire.joint_state`), ``sensor_msgs/msg/Imu`` (:mod:`~a1_leg_fk.wire.imu`),
Unitree's ``LowState`` of both kinds and ``SportModeState`` (:mod:`~a1_leg_fk.wire.lowstate`, on
the layouts of :mod:`~a1_leg_fk.wire.layout`). No ROS install and no ``rosbags`` here.
"""
