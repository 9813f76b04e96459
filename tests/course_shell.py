"""Terminals for tests that type a page's commands as a student would: each one a bash
reading commands one at a time, in a network namespace of its own, so the page's
`roscore` and `roslaunch` take ROS's default port 11311 without meeting anyone else's.

    with Namespace() as net:
        terminal = Terminal(net, cwd, env)
        status, output = terminal.run('rosnode list')
        background = terminal.start('roscore', log_path)
"""
import os
import select
import signal
import subprocess
import time
import uuid

DONE = '__course_doc_done_%s__' % uuid.uuid4().hex
STARTED = '__course_doc_started_%s__' % uuid.uuid4().hex


class Namespace:
    """A network namespace with loopback up, held open by a sleeping process."""

    def __init__(self):
        self._as_user = os.geteuid() != 0
        user = ['--user', '--map-root-user'] if self._as_user else []
        self.holder = subprocess.Popen(['unshare', '--net'] + user
                                       + ['sh', '-c', 'ip link set lo up && echo up && exec sleep infinity'],
                                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        said = self.holder.stdout.readline()
        if said.strip() != 'up':
            self.close()
            raise OSError('cannot make a network namespace: %s' % said.strip())

    def enter(self, argv):
        user = ['--user', '--preserve-credentials'] if self._as_user else []
        return ['nsenter', '--target', str(self.holder.pid), '--net'] + user + ['--'] + argv

    def close(self):
        self.holder.kill()
        self.holder.wait()

    def __enter__(self):
        return self

    def __exit__(self, *_exc):
        self.close()


class Background:
    """A command started in the background in a session of its own."""

    def __init__(self, command, pid, log_path):
        self.command, self.pid, self.log_path = command, pid, log_path

    def log(self):
        with open(self.log_path, errors='replace') as log:
            return log.read()

    def running(self):
        try:
            with open('/proc/%d/stat' % self.pid) as stat:
                return stat.read().rsplit(')', 1)[1].split()[0] != 'Z'
        except FileNotFoundError:
            return False

    def stop(self, wall_timeout=20.0):
        """Ctrl-C to its whole session, as a terminal's Ctrl-C; SIGKILL what lingers."""
        for sig, wait in ((signal.SIGINT, wall_timeout), (signal.SIGKILL, 5.0)):
            try:
                os.killpg(self.pid, sig)
            except ProcessLookupError:
                return
            deadline = time.monotonic() + wait
            while self.running() and time.monotonic() < deadline:
                time.sleep(0.1)
            if not self.running():
                return


class Terminal:
    """One bash, fed one command at a time; its stdout and stderr are one stream."""

    def __init__(self, net, cwd, env):
        self.process = subprocess.Popen(net.enter(['bash', '--noprofile', '--norc']), cwd=cwd, env=env,
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, start_new_session=True)
        self._buffer = b''
        self.run('exec 2>&1')

    def _send(self, text):
        self.process.stdin.write(text.encode() + b'\n')
        self.process.stdin.flush()

    def _read_until(self, marker, wall_timeout):
        """Output up to the marker line, and the number after the marker."""
        deadline = time.monotonic() + wall_timeout
        token = marker.encode() + b' '
        while True:
            at = self._buffer.find(token)
            if at >= 0:
                end = self._buffer.find(b'\n', at)
                if end >= 0:
                    output = self._buffer[:at].decode(errors='replace')
                    number = int(self._buffer[at + len(token):end])
                    self._buffer = self._buffer[end + 1:]
                    return output, number
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError('no end within %g s; printed so far:\n%s'
                                   % (wall_timeout, self._buffer.decode(errors='replace')[-4000:]))
            if self.process.poll() is not None:
                raise RuntimeError('the terminal ended; it printed:\n%s' % self._buffer.decode(errors='replace'))
            if select.select([self.process.stdout], [], [], min(remaining, 1.0))[0]:
                self._buffer += os.read(self.process.stdout.fileno(), 65536)

    def run(self, command, wall_timeout=300.0):
        """(exit status, output) of a command run to its end in this terminal."""
        self._send('%s\nprintf "\\n%s %%d\\n" $?' % (command, DONE))
        output, status = self._read_until(DONE, wall_timeout)
        return status, output

    def start(self, command, log_path, stdin='/dev/null'):
        """Start a command in the background, its output to log_path; its Background."""
        self._send('setsid %s > %s 2>&1 < %s &\nprintf "\\n%s %%d\\n" $!' % (command, log_path, stdin, STARTED))
        _output, pid = self._read_until(STARTED, 30.0)
        return Background(command, pid, log_path)

    def close(self):
        try:
            self.process.stdin.close()
        except BrokenPipeError:
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
