"""Child processes that are started together and stopped together.

Each child gets a session of its own, so SIGINT reaches a whole roslaunch
tree (roslaunch, its nodes) and not the caller. A command that starts them
runs under cleanup_on_signals(), so that SIGTERM (kill, a job scheduler, a
timeout) and SIGHUP (a closed terminal) stop them the way Ctrl-C does.
"""
import contextlib
import os
import signal
import socket
import subprocess
import time

# roslaunch escalates to SIGTERM and SIGKILL on its own within about 17 s;
# killing roslaunch itself sooner would orphan its nodes.
ROSLAUNCH_SHUTDOWN_S = 25.0


@contextlib.contextmanager
def cleanup_on_signals(signals=(signal.SIGTERM, signal.SIGHUP)):
    """Within the block, these signals raise KeyboardInterrupt in the main thread, as SIGINT does,
    so the same finally clauses stop every child; the old handlers come back afterwards."""
    def interrupt(signum, _frame):
        raise KeyboardInterrupt('signal %d' % signum)
    previous = {signum: signal.signal(signum, interrupt) for signum in signals}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def wait_until(ready, groups, wall_timeout=60.0, poll_s=0.2):
    """True once ready() is; False as soon as one of groups has died, or at the wall timeout."""
    deadline = time.monotonic() + wall_timeout
    while time.monotonic() < deadline and all(group.alive() for group in groups):
        if ready():
            return True
        time.sleep(poll_s)
    return False


def wait_or_kill(proc, wall_timeout):
    """Wait for proc to end; SIGKILL its process group if it has not within wall_timeout."""
    try:
        proc.wait(timeout=wall_timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


class ProcessGroup:
    def __init__(self, env=None, stop_timeout=ROSLAUNCH_SHUTDOWN_S):
        self.env = env
        self.stop_timeout = stop_timeout
        self.procs = []

    def start(self, cmd, log):
        proc = subprocess.Popen(list(cmd), env=self.env, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True)
        self.procs.append(proc)
        return proc

    def alive(self):
        return all(proc.poll() is None for proc in self.procs)

    def stop(self):
        """SIGINT to every child, newest first, then SIGKILL to any that outlives the timeout."""
        for proc in reversed(self.procs):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
        for proc in reversed(self.procs):
            wait_or_kill(proc, self.stop_timeout)
        self.procs = []


class MasterError(Exception):
    """A ROS master of our own could not be started; the message says why."""


class PortTaken(MasterError):
    """Something, most likely another ROS master, already listens on the port."""

    def __init__(self, port):
        super().__init__('port %d is taken, most likely by another ROS master' % port)
        self.port = port


def port_taken(port):
    """True when a socket listens on port, on any address (a ROS master listens on all of them)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        # A port that a closed connection still holds (TIME_WAIT) is free for a master too.
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(('', port))
        except OSError:
            return True
    return False


def free_port():
    """A TCP port that nothing listens on right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(('', 0))
        return sock.getsockname()[1]


class Launches(ProcessGroup):
    """roslaunch processes on one master port."""

    def __init__(self, port, env=None):
        super().__init__(env)
        self.port = port

    def start_master(self, log, wall_timeout=60.0):
        """Start a ROS master of this group's own on its port, stopped last with the group.

        roslaunch -p joins any master it finds on the port, and leaves its parameters
        there; this raises PortTaken instead, also when another master wins a race for it,
        and MasterError when the master does not come up."""
        import rosgraph  # here, so that the rest of this module needs no ROS
        if port_taken(self.port):
            raise PortTaken(self.port)
        master_proc = self.start(['rosmaster', '--core', '-p', str(self.port)], log)
        master = rosgraph.Master('/chase_tools', master_uri='http://localhost:%d' % self.port)

        def answers():
            try:
                return master.getPid()
            except Exception:  # noqa: BLE001 - not up yet: refused, reset, or not a master at all
                return None
        up = wait_until(answers, [self], wall_timeout)
        if master_proc.poll() is not None:
            if port_taken(self.port):
                raise PortTaken(self.port)
            raise MasterError('the ROS master for port %d exited at once (status %d)'
                              % (self.port, master_proc.returncode))
        if up and answers() != master_proc.pid:
            raise PortTaken(self.port)
        if not up:
            raise MasterError('the ROS master on port %d did not answer within %.0f s'
                              % (self.port, wall_timeout))

    def launch(self, *args, log):
        return self.start(['roslaunch', '-p', str(self.port)] + list(args), log)
