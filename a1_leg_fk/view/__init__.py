"""A recorded run as a Rerun recording: the robot (:mod:`.robot`), the feet, paths and time
series (:mod:`.columns`), written atomically (:mod:`.recording`). Needs ``rerun-sdk`` (the
``view`` extra); no ROS.
"""
