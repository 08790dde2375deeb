"""Gait analysis, no ROS: world feet -> contacts, stride metrics and the gait's name
(:func:`~a1_leg_fk.gait.analysis.analyze_gait`); and the demo gait the demo node publishes.
"""
