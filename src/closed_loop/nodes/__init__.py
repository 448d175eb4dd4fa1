"""The rospy layer: the only modules of closed_loop that import rospy or message packages.

``sim_node`` (the simulator behind the topics of a mobile base; ``sensor_messages`` turns its sensors'
readings into messages), ``controller_node`` (the one host of every controller core), and the tools:
``obstacle_detector``, ``vision_node``, ``cmd_vel_guard``, ``cmd_vel_marker``, ``velocity_publisher``,
``record_bag``. ``common`` and ``conversions`` hold what they share (start-up, ``~`` parameters,
dynamic_reconfigure, messages to plain values); ``screen`` is the virtual screen (Xvfb) that the screenshot
tool and the rviz tests show rviz on.

May import anything in the package.
"""
