"""What a worker of a sweep's local cluster does as it starts (Dask's worker preload, ``dask_setup``).

Ctrl-C in a terminal reaches every process of the sweep's group: the sweep itself stops its cluster and says so
in one line, so a local worker leaves SIGINT to it (else each prints Python's KeyboardInterrupt traceback as it
dies), and keeps Dask's own log lines to itself unless the sweep is --verbose: a task "ended with
CancelledError", a heartbeat that found the scheduler gone as the sweep ended (the sweep says what became of
every episode, and runs a lost worker's again). A cluster of the user's (``--scheduler``) is left as it is.
"""
import logging
import signal

from closed_loop.sim import quiet


def dask_setup(worker):
    """Dask calls this in the worker process, in its main thread, before the worker takes a task."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if not quiet.verbose():
        logging.getLogger('distributed').setLevel(logging.CRITICAL)
