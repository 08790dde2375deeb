"""State estimation from the legs, without ROS: contacts and leg odometry."""
