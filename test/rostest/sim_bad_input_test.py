#!/usr/bin/env python3
"""sim_node refuses a malformed world or a bad parameter: it exits non-zero with a message naming it."""
import os
import subprocess
import unittest

import rospkg
import rostest

# Only a bound that catches a hang: the node is expected to exit within seconds.
EXIT_LIMIT_S = 60


def run_sim(name, *args):
    # A node name of its own per run: rosrun's _param:= values stay on the parameter server.
    proc = subprocess.run(['rosrun', 'closed_loop', 'sim_node', '__name:=' + name] + list(args),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=EXIT_LIMIT_S)
    return proc.returncode, proc.stdout.decode(errors='replace')


class SimBadInput(unittest.TestCase):
    def test_malformed_world_exits_with_its_message(self):
        path = os.path.join(rospkg.RosPack().get_path('closed_loop'), 'test', 'worlds', 'bad_world.yaml')
        code, out = run_sim('bad_world_sim', '_world:=' + path)
        self.assertNotEqual(code, 0, out)
        self.assertIn('bad_world.yaml', out)
        self.assertIn('obstacles[0].size', out)

    def test_unknown_world_names_the_available_ones(self):
        code, out = run_sim('unknown_world_sim', '_world:=no_such_world')
        self.assertNotEqual(code, 0, out)
        self.assertIn('no_such_world', out)
        self.assertIn('wall', out)

    def test_bad_parameter_exits_naming_it(self):
        code, out = run_sim('bad_param_sim', '_scan_rate_hz:=-1.0')
        self.assertNotEqual(code, 0, out)
        self.assertIn('~scan_rate_hz', out)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'sim_bad_input', SimBadInput)
