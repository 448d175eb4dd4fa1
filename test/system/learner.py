"""A learner at a terminal, for the tests that follow a docs page as typed: each command in a shell of its own (bash,
with this package's env.sh sourced: the test's environment), in a home of its own, on a graph whose master is on
a free loopback port. A command that runs until Ctrl-C keeps its shell; ``ctrl_c`` ends what is running."""
import os
import re
import signal
import subprocess

import yaml

from conftest import ROOT, _logging_under, free_port, kill_group, master_pid, ros_env, stop, wait_for, wait_master

FENCE = re.compile(r'^```bash\n(.*?)^```$', re.M | re.S)
HEADING = re.compile(r'^## (.+)$', re.M)
COMMENT = re.compile(r'\s+#\s?(.*)$')
#: What ``rostopic echo`` says between messages while it waits (not a message).
ECHO_NOTES = re.compile(r'^(WARNING: no messages received.*|Is /clock being published\?|WARNING: topic \[.*\] does '
                        r'not appear to be published yet)\n', re.M)
#: Bounds that only catch hangs.
COMMAND_S = 300.0


def page_commands(page):
    """``{section: [(command, what the page says it shows)]}`` of every ```bash block of ``docs/page``, by the
    ``## `` heading it is under, in the page's order (a line's ``# ...`` is what it says; '' where it says
    nothing)."""
    with open(os.path.join(ROOT, 'docs', page)) as f:
        text = f.read()
    sections = {}
    for block in FENCE.finditer(text):
        headings = HEADING.findall(text[:block.start()])
        for line in block.group(1).splitlines():
            if line.strip() and not line.lstrip().startswith('#'):
                said = COMMENT.search(line)
                sections.setdefault(headings[-1] if headings else '', []).append(
                    (line[:said.start()] if said else line.rstrip(), said.group(1) if said else ''))
    return sections


class Shell:
    """One command running in a shell of its own: its output so far, and the messages a ``rostopic echo`` printed."""

    def __init__(self, command, process, log_path):
        self.command, self.process, self.log_path = command, process, log_path

    def output(self):
        with open(self.log_path, errors='replace') as f:
            return f.read()

    def messages(self):
        """The whole messages ``rostopic echo`` has printed so far, each as YAML's value."""
        documents = ECHO_NOTES.sub('', self.output()).split('\n---\n')[:-1]
        return [yaml.safe_load(d) for d in documents if d.strip()]

    def wait_messages(self, count, timeout_s=60.0, since=0):
        return wait_for(lambda: (lambda m: m if len(m) >= since + count else None)(self.messages()), timeout_s,
                        '%d messages from %r' % (count, self.command))[since:]


class Learner:
    """The shells of one learner. ``run`` types a command and waits for its end; ``start`` one that keeps its shell."""

    def __init__(self, tmp_path):
        self.home = tmp_path / 'home'
        self.home.mkdir()
        self.logs = tmp_path / 'shells'
        self.logs.mkdir()
        self.port = free_port()
        # A terminal shows each line a command prints as it comes; into a file Python would print in blocks.
        self.env = ros_env(tmp_path, self.port, HOME=str(self.home), PYTHONUNBUFFERED='1')
        self.running = []
        self.count = 0

    def _log(self):
        self.count += 1
        return str(self.logs / ('%02d.log' % self.count))

    def start(self, command, cwd=None, **env):
        log_path = self._log()
        with open(log_path, 'w') as log:
            log.write('')
            process = subprocess.Popen(['bash', '-c', command], cwd=str(cwd or self.home),
                                       env=dict(self.env, **env), stdout=log, stderr=subprocess.STDOUT,
                                       start_new_session=True)
        shell = Shell(command, process, log_path)
        self.running.append(shell)
        if command.startswith(('roslaunch ', 'roscore')):
            wait_master(self.port, timeout_s=60.0)      # a learner types on once the launch is up
        return shell

    def run(self, command, cwd=None, timeout_s=COMMAND_S):
        """(exit status, output) of a command that ends by itself."""
        done = subprocess.run(['bash', '-c', command], cwd=str(cwd or self.home), env=self.env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                              timeout=timeout_s)
        with open(self._log(), 'w') as log:
            log.write('$ %s\n%s' % (command, done.stdout))
        return done.returncode, done.stdout

    def ctrl_c(self, *shells):
        """Ctrl-C in the given shells, the newest first; with none given, in every shell still running, and then
        the graph is gone (no master left on its port)."""
        for shell in reversed(shells or list(self.running)):
            stop(shell.process, signal.SIGINT)
            if shell in self.running:
                self.running.remove(shell)
        if not shells:
            wait_for(lambda: master_pid(self.port) is None, 30.0, 'the master gone after Ctrl-C everywhere')

    def close(self):
        for shell in reversed(self.running):
            kill_group(shell.process)
        self.running = []
        for pid in _logging_under(self.env['ROS_LOG_DIR']):      # a master or rosout roslaunch left behind
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
