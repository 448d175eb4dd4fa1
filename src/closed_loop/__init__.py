"""closed_loop: a sense-decide-act teaching and test package for ROS 1 with a pybullet robot."""
