"""Inverse kinematics of three-joint legs, no ROS: the four-feet API and its results
(:mod:`~a1_leg_fk.kinematics.ik.four_legs`), one leg's solver
(:mod:`~a1_leg_fk.kinematics.ik.leg_solver`), the closed form and its generated code, the damped
least-squares search and the seed rule.
"""
