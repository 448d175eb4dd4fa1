"""scenario_test: a rostest test node that waits for the scenario judge's verdict and checks it against what
the test file says must hold. The judging is scenario_judge's; this only compares."""
import json
import threading
import unittest

import rospy
import rostest
from std_msgs.msg import String

from closed_loop.batch.judge import problems

#: How long to wait for the verdict (s of wall time) unless ~wait says; rostest's time-limit also applies.
DEFAULT_WAIT_S = 600.0


def expectations():
    """What must hold, from the node's parameters: ``~expect`` (an outcome, or several separated by commas;
    default reached), ``~max_contacts`` (default 0), ``~min_clearance`` (m; default none), ``~within`` (s of
    simulated time; default none)."""
    outcomes = [o.strip() for o in str(rospy.get_param('~expect', 'reached')).split(',') if o.strip()]
    return {'outcomes': outcomes, 'max_contacts': int(rospy.get_param('~max_contacts', 0)),
            'min_clearance': rospy.get_param('~min_clearance', None), 'within': rospy.get_param('~within', None)}


class Scenario(unittest.TestCase):
    def test_the_verdict_is_what_the_test_expects(self):
        rospy.init_node('scenario_test')
        expect = expectations()
        topic = rospy.get_param('~verdict_topic', '/scenario_judge/verdict')
        got = threading.Event()
        box = {}

        def on_verdict(msg):
            box['verdict'] = json.loads(msg.data)
            got.set()
        rospy.Subscriber(topic, String, on_verdict, queue_size=1)
        rospy.on_shutdown(got.set)       # (killed, or the master gone: end now, not after ~wait)
        wait_s = float(rospy.get_param('~wait', DEFAULT_WAIT_S))
        if not got.wait(wait_s):
            self.fail('no verdict on %s within %g s of wall time' % (topic, wait_s))
        if 'verdict' not in box:
            self.fail('shut down before a verdict came on %s' % topic)
        verdict = box['verdict']
        found = problems(verdict, expect)
        if found:
            rospy.logerr('scenario FAILED: %s; the robot: %s', '; '.join(found), verdict['why'])
            self.fail('scenario FAILED: %s; the robot: %s' % ('; '.join(found), verdict['why']))


def main():
    rostest.rosrun('closed_loop', 'scenario_test', Scenario)
