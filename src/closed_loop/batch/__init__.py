"""The batch path, free of ROS: an episode is the simulator and a controller's core in lockstep
(``episode``); a sweep is a grid of episodes on Dask (``sweep_file``, ``sweep``); ``tune_thresholds`` is the
lesson's tuning question as a sweep.

May import: ``sim``, ``controllers``, ``control`` and the shared helpers. Never ``nodes`` or rospy.
"""
