"""The simulator, free of ROS: a pybullet world and robot (``simulation``, ``robot_body``, ``drive``), worlds
read from YAML (``world``, ``world_robots``, ``obstacles``, ``shapes``), from a map (``occupancy_map``) or a
Gazebo world (``gazebo_world``, its meshes' footprints by ``mesh_footprint`` and ``footprint_kernel``) or
generated (``clutter``), robot
profiles (``profiles``), the planar ray caster (``planar_rays``, its loop compiled in ``planar_kernel``), the
sensors as plugins (``sensors``), their schedule on simulated time (``scheduler``), and a robot with all its
sensors from flat parameters (``rig``).

May import: pybullet, numpy, cv2, trimesh, and the package's shared helpers (``closed_loop.settings``, ``yaml_check``,
``geometry``, ``robot_model``, ``commands``, ``paths``, ``compiled``: numba's, for ``planar_kernel`` and ``footprint_kernel``). Never
``control``, ``controllers``, ``batch`` or ``nodes``: the simulator knows nothing of what drives it.
"""
