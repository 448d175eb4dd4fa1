"""start_when_ready: starts a simulator that waits paused at t = 0 (``sim.launch paused:=true``) once the
controller is up and its connections are made (``closed_loop.nodes.graph_ready``), then ends (status 0; 1 when
the simulator cannot be started). Parameters: :class:`closed_loop.batch.judge.StartSettings`, ``~unpause``
required (``demo.launch paused:=true`` sets the simulator's ``/sim/unpause_physics``)."""
import sys

import rospy

from closed_loop.batch.judge import StartSettings
from closed_loop.nodes import graph_ready
from closed_loop.nodes.common import init_node, load_settings


def main():
    init_node('start_when_ready')
    start = load_settings(StartSettings)
    if not start.unpause:
        rospy.logfatal("~unpause: expected the paused simulator's unpause service (e.g. /sim/unpause_physics), got ''")
        sys.exit(2)
    sys.exit(0 if graph_ready.start_when_ready(start) else 1)
