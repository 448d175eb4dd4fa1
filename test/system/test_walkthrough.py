"""docs/own_controller.md's walk-through, followed as written: from an empty workspace in a new home, its commands
and each file it shows (marked ``<!-- walkthrough: ... -->`` before its block) make a rospy package whose rostest
passes; asked for what the node cannot do, the test fails with a line that reads as a failure."""
import os
import re
import stat
import subprocess

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
PAGE = os.path.join(ROOT, 'docs', 'own_controller.md')
MARKED = re.compile(r'^<!-- walkthrough: (.+?) -->\n```\w*\n(.*?)^```$', re.M | re.S)
TIMEOUT_S = 600


def blocks():
    with open(PAGE) as f:
        return {key: text for key, text in MARKED.findall(f.read())}


def bash(script, home, env):
    """The page's shell lines, as a user types them in a shell with this package's env.sh sourced (the test's own
    environment) and ``home`` as their home; returns (exit status, output)."""
    done = subprocess.run(['bash', '-e', '-c', script], env=dict(env, HOME=str(home)), cwd=str(home),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=TIMEOUT_S)
    return done.returncode, done.stdout


def test_the_walkthrough_builds_from_an_empty_workspace_and_its_test_passes_then_fails_as_a_failure(tmp_path):
    page = blocks()
    assert set(page) == {'commands', 'scripts/wall_stopper', 'CMakeLists.txt +=', 'package.xml +=',
                         'test/wall_stopper.test', 'build'}, sorted(page)
    env = dict(os.environ, ROS_HOME=str(tmp_path / '.ros'))
    code, out = bash(page['commands'], tmp_path, env)
    assert code == 0, out
    package = tmp_path / 'my_ws' / 'src' / 'wall_stopper'
    for name in ('scripts/wall_stopper', 'test/wall_stopper.test'):
        (package / name).write_text(page[name])
    node = package / 'scripts' / 'wall_stopper'
    node.chmod(node.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)          # the page's chmod +x
    with open(str(package / 'CMakeLists.txt'), 'a') as f:
        f.write('\n' + page['CMakeLists.txt +='])
    manifest = (package / 'package.xml').read_text()
    assert manifest.count('</package>') == 1
    (package / 'package.xml').write_text(manifest.replace('</package>', page['package.xml +='] + '</package>'))
    code, out = bash(page['build'], tmp_path, env)
    assert code == 0 and '* RESULT: SUCCESS' in out, out[-4000:]
    # What it cannot do: there is no goal to reach. rostest's "[Testcase: ...] ... ok" only says the test node
    # ran; the failure follows, in the test's words, and the summary and exit status say FAIL.
    too_much = package / 'test' / 'wall_stopper_reaches.test'
    too_much.write_text(page['test/wall_stopper.test'].replace('value="stopped"', 'value="reached"'))
    code, out = bash('cd ~/my_ws && source devel/setup.bash && rostest wall_stopper wall_stopper_reaches.test',
                     tmp_path, env)
    assert code != 0 and '* RESULT: FAIL' in out, out[-4000:]
    failed = [line for line in out.splitlines() if line.startswith('scenario FAILED: ')]
    assert len(failed) == 1 and failed[0].startswith('scenario FAILED: outcome stopped, expected reached; the '
                                                     'robot: stopped at (2.'), out[-4000:]
    assert 'least clearance 0.' in failed[0] and '0 contacts' in failed[0], failed
