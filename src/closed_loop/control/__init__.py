"""The control cores, free of ROS and of the simulator: plain numbers and arrays in and out.

Scan geometry (``scan``), the stop/slow/cruise rule (``decisions``), the lesson's state machine
(``state_machine``), the loop's shared settings and staleness rule (``loop``), the reactive navigator
(``navigator``) over its local planner (``local_planner``, ``wavefront``, ``clearance_field``,
``scan_memory``, and their compiled loops ``wave_kernel`` and ``arc_kernel``), with its escape from a pocket
(``escape`` over ``hybrid_kernel``) and the exact check of slow moves (``move_check``), the command guard (``guard``),
tracking and fusion (``tracking``, ``fusion``, ``fusion_navigator``), red-object vision (``vision``), what a
controller draws (``drawing``) and the command arrow (``markers``).

May import: numpy, cv2 and the package's shared helpers (``closed_loop.compiled``: numba's, for the
``*_kernel`` modules). Never pybullet, ``sim``, ``controllers``, ``batch`` or ``nodes``.
"""
