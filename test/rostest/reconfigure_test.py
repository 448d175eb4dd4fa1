#!/usr/bin/env python3
"""demo.launch in `wall`, changed while it runs with the stock tool (`rosrun dynamic_reconfigure dynparam`):
the effective defaults are on the parameter server; stop above slow is refused as dynamic_reconfigure servers
refuse (the values in force kept, the tool ends cleanly, the reason logged once as a warning); both thresholds
change in one call; `stop_distance 0.8` set while the robot cruises far from the wall makes it rest 0.70-0.80 m from the
wall (it rests 0.40-0.50 m at the default 0.5 m, loop_wall), judged on ground truth; the detector's
threshold is live too."""
import os
import subprocess
import sys
import unittest

import rospy
import rostest
from dynamic_reconfigure.client import Client
from rosgraph_msgs.msg import Log
from std_msgs.msg import UInt32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.control.decisions import StopSettings  # noqa: E402
from closed_loop.control.scan import DetectorSettings  # noqa: E402

WALL_NEAR_FACE_X_M = 3.0     # worlds/wall.yaml; the LIDAR is at the robot's centre (urdf/closed_loop.urdf)
NEW_STOP_DISTANCE_M = 0.8
# Past the new stop distance by at most this (braking from slow speed within one control period).
STOP_BAND_M = 0.10
CHANGE_BEFORE_CLEARANCE_M = 2.0   # the change is made while the wall is farther than this
TOOL_TIMEOUT_S = 30.0


def dynparam(*args):
    """Run the stock dynparam tool (argument list, no shell); return (exit status, output)."""
    done = subprocess.run(['rosrun', 'dynamic_reconfigure', 'dynparam'] + list(args), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True, timeout=TOOL_TIMEOUT_S)
    return done.returncode, done.stdout


class Reconfigure(unittest.TestCase):
    def test_change_stop_distance_mid_run(self):
        rospy.init_node('reconfigure_test')
        warnings = []
        rospy.Subscriber('/rosout', Log, lambda m: warnings.append(m.msg) if m.level >= Log.WARN else None)
        truth = harness.GroundTruth()
        judged = harness.Judged()
        contacts = harness.Latest('contact_count', UInt32)
        defaults = StopSettings()
        # A node serves ~set_parameters once it has written its effective parameters.
        for node in ('/stop_on_obstacle', '/obstacle_detector'):
            rospy.wait_for_service(node + '/set_parameters', timeout=harness.WAIT_FOR_TOPIC_S)
        self.assertEqual(rospy.get_param('/stop_on_obstacle/stop_distance'), defaults.stop_distance)
        self.assertEqual(rospy.get_param('/stop_on_obstacle/scan_timeout'), defaults.scan_timeout)
        self.assertEqual(rospy.get_param('/obstacle_detector/warn_distance'), DetectorSettings().warn_distance)

        # Wait until it cruises, still far from the wall.
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.3)
        self.assertGreater(WALL_NEAR_FACE_X_M - truth.xy()[0], CHANGE_BEFORE_CLEARANCE_M)

        status, out = dynparam('set', '/stop_on_obstacle', 'stop_distance', str(NEW_STOP_DISTANCE_M))
        self.assertEqual(status, 0, out)
        self.assertGreater(WALL_NEAR_FACE_X_M - truth.xy()[0], defaults.slow_distance,
                           'the change came too late to show')
        status, out = dynparam('get', '/stop_on_obstacle')
        self.assertEqual(status, 0, out)
        self.assertIn("'stop_distance': %r" % NEW_STOP_DISTANCE_M, out)
        self.assertEqual(rospy.get_param('/stop_on_obstacle/stop_distance'), NEW_STOP_DISTANCE_M)

        # Until the judge says it came to rest.
        rest = judged.rest(timeout_s=120.0)
        self.assertEqual(rest.outcome, 'stopped', rest.why)
        clearance = WALL_NEAR_FACE_X_M - rest.final_pose[0]
        self.assertTrue(NEW_STOP_DISTANCE_M - STOP_BAND_M <= clearance <= NEW_STOP_DISTANCE_M,
                        'rested %.3f m from the wall, expected %.2f-%.2f m'
                        % (clearance, NEW_STOP_DISTANCE_M - STOP_BAND_M, NEW_STOP_DISTANCE_M))
        self.assertEqual(contacts.wait().data, 0)

        # At rest: stop above slow is refused as dynamic_reconfigure servers refuse: the tool ends cleanly, the
        # values in force stay (on the parameter server too), and the node says why once, as a warning.
        status, out = dynparam('set', '/stop_on_obstacle', 'stop_distance', '1.5')
        self.assertEqual(status, 0, out)
        self.assertNotIn('Traceback', out)
        client = Client('/stop_on_obstacle', timeout=TOOL_TIMEOUT_S)
        self.assertEqual(client.get_configuration(TOOL_TIMEOUT_S)['stop_distance'], NEW_STOP_DISTANCE_M)
        self.assertEqual(rospy.get_param('/stop_on_obstacle/stop_distance'), NEW_STOP_DISTANCE_M)
        status, out = dynparam('get', '/stop_on_obstacle')
        self.assertIn("'stop_distance': %r" % NEW_STOP_DISTANCE_M, out)
        deadline = rospy.Time.now() + rospy.Duration(TOOL_TIMEOUT_S)
        while not [w for w in warnings if 'expected more than stop_distance' in w] and rospy.Time.now() < deadline:
            rospy.sleep(0.1)
        refused = [w for w in warnings if 'expected more than stop_distance' in w]
        self.assertEqual(len(refused), 1, warnings)
        self.assertIn('reconfigure refused, the values in force are kept', refused[0])
        # Both thresholds in one call, as the docs show.
        status, out = dynparam('set', '/stop_on_obstacle', '{slow_distance: 2.0, stop_distance: 1.5}')
        self.assertEqual(status, 0, out)
        both = client.get_configuration(TOOL_TIMEOUT_S)
        self.assertEqual((both['slow_distance'], both['stop_distance']), (2.0, 1.5))
        client.update_configuration({'slow_distance': defaults.slow_distance, 'stop_distance': defaults.stop_distance})

        # The detector's threshold is live as well.
        detector = Client('/obstacle_detector', timeout=TOOL_TIMEOUT_S)
        self.assertEqual(detector.update_configuration({'warn_distance': 0.9})['warn_distance'], 0.9)
        self.assertEqual(rospy.get_param('/obstacle_detector/warn_distance'), 0.9)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'reconfigure', Reconfigure)
