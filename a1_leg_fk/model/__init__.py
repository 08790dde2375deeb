"""The robot model, no ROS and no numpy: URDF XML -> :class:`~a1_leg_fk.model.urdf.RobotModel`
(:mod:`~a1_leg_fk.model.urdf`, the one loader and :class:`~a1_leg_fk.model.urdf.LegFkError`), and
the four legs found in it: foot discovery, leg order, joint naming (:mod:`~a1_leg_fk.model.legs`).
"""
