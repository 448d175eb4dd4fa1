"""Thin rospy layer: the only modules of closed_loop that import rospy or message packages."""
