"""Helpers shared by the node classes: settings from ``~`` parameters, stamps, shutdown."""
import sys

import rospy

from closed_loop.settings import SettingsError, from_params


def load_settings(cls):
    """Read ``cls`` from the node's private parameters; on a bad value log it and exit with status 2."""
    try:
        return from_params(cls, rospy.get_param)
    except SettingsError as error:
        rospy.logfatal('%s: bad parameter %s', rospy.get_name(), error)
        sys.exit(2)


def stamp_to_sec(stamp):
    """A ``rospy.Time`` (or ``genpy.Time``) as float seconds."""
    return stamp.secs + stamp.nsecs * 1e-9
