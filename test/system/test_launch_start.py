"""Where the robot starts, as a launch file is given it: ``start:='x y yaw'``, or ``start_x``, ``start_y`` and
``start_yaw`` (a world file with no start of its own, a map of a building), read by roslaunch's own loader
from every launch file that starts the simulator, and the simulator's ``~start`` as it would take it."""
import math
import os

import pytest
import roslaunch.config
import roslaunch.xmlloader

from closed_loop.settings import SettingsError
from closed_loop.sim.simulation import SimSettings

LAUNCH = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'launch')


def sim_start(launch, *args):
    """The simulator's ``~start`` parameter as roslaunch sets it from ``launch`` given ``args`` (name:=value)."""
    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader().load(os.path.join(LAUNCH, launch), config, argv=['roslaunch'] + list(args),
                                         verbose=False)
    (start,) = [p.value for name, p in config.params.items() if name.endswith('/sim/start')]
    return SimSettings(start=start).start_pose


@pytest.mark.parametrize('launch', ['sim.launch', 'demo.launch', 'avoid.launch', 'fusion.launch', 'scenario.launch'])
def test_the_start_is_given_as_one_arg_or_three(launch):
    assert sim_start(launch) is None                                    # the world's own
    assert sim_start(launch, 'start:=1 2 0.5') == (1.0, 2.0, 0.5)
    assert sim_start(launch, 'start_x:=1.5', 'start_y:=-2') == (1.5, -2.0, 0.0)
    assert sim_start(launch, 'start_x:=1.5', 'start_y:=-2', 'start_yaw:=%r' % math.pi) == (1.5, -2.0, math.pi)


@pytest.mark.parametrize('args, message', [
    (('start_x:=1.5',), "got '1.5  0'"),
    (('start:=1 2 3', 'start_x:=1', 'start_y:=2'), "got 'both start:=1 2 3 and start_x, start_y'"),
    (('start_x:=one', 'start_y:=2'), "got 'one 2 0'"),
])
def test_half_a_start_or_two_starts_are_refused_naming_the_args(args, message):
    with pytest.raises(SettingsError) as error:
        sim_start('sim.launch', *args)
    assert "~start: expected 'x y yaw'" in str(error.value) and message in str(error.value), str(error.value)
