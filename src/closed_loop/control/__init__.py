"""The control cores, free of ROS and of the simulator: plain numbers and arrays in and out.

Scan geometry (``scan``), the stop/slow/cruise rule (``decisions``), the lesson's state machine
(``state_machine``), the loop's shared settings and staleness rule (``loop``), the one rule for "is this move
safe?" and the one motion predictor (``safety``, its loop compiled in ``arc_kernel``), the reactive navigator
stage by stage (the ``navigation`` sub-package: its ``__init__`` lists the stages), the command guard
(``guard``), tracking and fusion (``tracking``, ``fusion``, ``fusion_navigator``), red-object vision
(``vision``), what a controller draws (``drawing``) and the command arrow (``markers``).

May import: numpy, cv2 and the package's shared helpers (``closed_loop.compiled``: numba's, for the
``*_kernel`` modules). Never pybullet, ``sim``, ``controllers``, ``batch`` or ``nodes``.
"""
