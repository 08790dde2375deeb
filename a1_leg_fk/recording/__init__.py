"""Recorded runs without a ROS install: open any ROS 1 / ROS 2 bag (rosbags, imported lazily),
decode JointState straight from its bytes, compute the feet block by block
(:func:`~a1_leg_fk.recording.trajectories.read_foot_trajectories`), the base pose, and the CSV and
bag writers.
"""
