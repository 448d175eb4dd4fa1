"""The tutorial's port of the lesson's stop-on-obstacle node, as it stands in docs/tutorial.md, drives the
simulated robot at the wall and stops it short, with no contact (ground truth)."""
import json
import subprocess
import sys
import textwrap

from conftest import doc_code, stop

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
    sim = subprocess.Popen(['roslaunch', 'closed_loop', 'sim.launch', 'world:=wall', 'camera:=false'], env=roscore,
                           stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, start_new_session=True)
    lesson = subprocess.Popen([sys.executable, str(tmp_path / 'lesson_stop.py')], env=roscore,
                              stdout=open(str(tmp_path / 'lesson.log'), 'w'), stderr=subprocess.STDOUT,
                              start_new_session=True)
    try:
        watched = subprocess.run([sys.executable, '-c', WATCH], env=roscore, stdout=subprocess.PIPE,
                                 universal_newlines=True, timeout=120)
    finally:
        stop(lesson)
        stop(sim)
    end = json.loads(watched.stdout.strip().splitlines()[-1])
    assert end['contacts'] == 0 and abs(end['speed']) < 1e-3, end
    # The LIDAR sits at base_footprint: it stops once the wall is under 0.5 m, having slowed to 0.2 m/s.
    assert 0.3 < WALL_FACE_X - end['x'] < 0.5, end
