"""Forward kinematics of a quadruped's four feet from a URDF, and a ROS 2 node around it.

The pure-Python core (no ROS imports) is :mod:`a1_leg_fk.urdf` (URDF reading),
:mod:`a1_leg_fk.legs` (leg discovery, joint naming) and :mod:`a1_leg_fk.kinematics`
(positions, Jacobians, velocities, limits, reach)::

    from a1_leg_fk.kinematics import Quadruped
    robot = Quadruped.from_urdf()            # the embedded Unitree A1
    feet = robot.fk([0.0, 0.8, -1.5] * 4)    # (4, 3) metres, FR FL RR RL, base frame
"""
