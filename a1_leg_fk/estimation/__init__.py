"""State estimation from the legs, without ROS: the force contact rule (:mod:`.contacts`) and leg
odometry (stance, rolling feet, slip rejection, the estimator and its feed, IMU readings).
"""
