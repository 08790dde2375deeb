"""Estimation from joint states, without ROS: foot forces and contacts."""
