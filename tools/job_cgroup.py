"""A cgroup for each job of ``tools/run_tests.py``, to count the CPU time of every process of the job."""
import os
import time


#: Where a job's every process can be counted: a cgroup of its own under one of these (cgroup v1's cpuacct, or
#: cgroup v2), where this machine lets the tests make one (as root). Its processes' descendants stay in it wherever
#: they are reparented (a sweep's Dask workers, a kept graph's simulator), which the job's own count (rusage: the
#: descendants it waited for) leaves out: for a sweep of graph episodes, less than half of what it took.
CGROUP_ROOTS = (('/sys/fs/cgroup/cpuacct', 'cpuacct.usage', 1e-9), ('/sys/fs/cgroup', 'cpu.stat', 1e-6))


class JobCgroup:
    """A cgroup for one job's processes, or none where it cannot be made (then ``seconds()`` is None)."""

    def __init__(self, name):
        self.path = self.usage = None
        for root, usage, unit in CGROUP_ROOTS:
            if os.path.isfile(os.path.join(root, usage)) or os.path.isfile(os.path.join(root, 'cgroup.controllers')):
                path = os.path.join(root, 'closed_loop_test-%d-%s' % (os.getpid(), name))
                try:
                    os.makedirs(path, exist_ok=True)
                except OSError:
                    continue
                if os.path.isfile(os.path.join(path, usage)):
                    self.path, self.usage, self.unit = path, usage, unit
                    return
                os.rmdir(path)

    def enter(self):
        """In the job's first process, before it runs the job: join the cgroup (nothing where there is none)."""
        if self.path is not None:
            try:
                with open(os.path.join(self.path, 'cgroup.procs'), 'w') as f:
                    f.write(str(os.getpid()))
            except OSError:
                pass

    def seconds(self):
        """CPU seconds of every process that was in the cgroup; None without one."""
        if self.path is None:
            return None
        try:
            with open(os.path.join(self.path, self.usage)) as f:
                text = f.read()
        except OSError:
            return None
        value = text.split()[0] if self.usage == 'cpuacct.usage' else \
            next((line.split()[1] for line in text.splitlines() if line.startswith('usage_usec')), None)
        return None if value is None else int(value) * self.unit

    def close(self, tries=1):
        """Remove the cgroup; where a process of the job outlived it (a cluster's worker ending), it is kept in LEFT
        and tried again at the end of the run, ``tries`` times a second."""
        for _ in range(tries):
            try:
                if self.path is not None:
                    os.rmdir(self.path)
                return
            except OSError:
                time.sleep(1.0 if tries > 1 else 0.0)
        LEFT.append(self)


LEFT = []
