"""The batch path, free of ROS: an episode, checked (``spec``), runs as the simulator and a controller's core in
lockstep (``lockstep``) or as a ROS graph of its own (``graph_episode``), either through ``episode``; a sweep is a grid of episodes on Dask (``sweep_file``, ``sweep``); ``tune_thresholds`` is the
lesson's tuning question as a sweep.

May import: ``sim``, ``controllers``, ``control`` and the shared helpers. Never ``nodes`` or rospy.
"""
