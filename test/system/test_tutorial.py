"""The tutorial's port of the lesson's stop-on-obstacle node, as it stands in docs/tutorial.md, drives the
simulated robot at the wall and stops it short, with no contact (ground truth)."""
import sys
import textwrap

from conftest import doc_code, drive_in_sim

WALL_FACE_X = 3.0          # worlds/wall.yaml
WATCH = textwrap.dedent('''
    import json, time
    import rospy
    from nav_msgs.msg import Odometry
    from std_msgs.msg import UInt32
    rospy.init_node('watch')
    truth, contacts = [], []
    rospy.Subscriber('/base_pose_ground_truth', Odometry, truth.append)
    rospy.Subscriber('/contact_count', UInt32, lambda m: contacts.append(m.data))
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:
        time.sleep(0.2)
        moved = [m for m in truth if m.pose.pose.position.x > 1.0]
        if moved and abs(truth[-1].twist.twist.linear.x) < 1e-3 and \\
                truth[-1].header.stamp.to_sec() - moved[0].header.stamp.to_sec() > 6.0:
            break
    print(json.dumps({'x': truth[-1].pose.pose.position.x, 'speed': truth[-1].twist.twist.linear.x,
                      'contacts': contacts[-1] if contacts else None}))
''')


def test_the_lessons_node_in_ros1_stops_the_robot_at_the_wall(tmp_path, roscore):
    (tmp_path / 'lesson_stop.py').write_text(doc_code('tutorial.md', '<!-- lesson-port -->'))
    end = drive_in_sim(roscore, tmp_path, [sys.executable, str(tmp_path / 'lesson_stop.py')], WATCH)
    assert end['contacts'] == 0 and abs(end['speed']) < 1e-3, end
    # The LIDAR sits at base_footprint: it stops once the wall is under 0.5 m, having slowed to 0.2 m/s.
    assert 0.3 < WALL_FACE_X - end['x'] < 0.5, end
