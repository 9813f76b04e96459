"""Logs of a submission's processes, kept to a bounded size.

A node that prints without end must cost neither the grader's memory nor the
teacher's disk: of each log, the first and the last half of the allowance
are kept, and the bytes between are counted and said in the file:

    [the grader cut 1234567890 bytes (1.1 GiB) here: it keeps the first and last 1 MiB of each log]

Pure: no ROS.
"""
import collections
import os
import signal
import subprocess
import threading
import time
from dataclasses import dataclass

from chase_tools.grading.limits import size_text

READ_CHUNK = 65536


def cut_line(count, keep, allowance=None):
    """The line that stands for count bytes cut; allowance, when larger than keep, is what the
    whole file may hold, of which earlier starts of the same process used the rest."""
    if allowance is not None and allowance > keep:
        return ('\n[the grader cut %d bytes (%s) here: it keeps %s of each log however often '
                'its launch starts, and earlier starts had used all but %s]\n'
                % (count, size_text(count), size_text(allowance), size_text(keep)))
    return ('\n[the grader cut %d bytes (%s) here: it keeps the first and last %s of each log]\n'
            % (count, size_text(count), size_text(keep // 2)))


class LogCap:
    """The first and last keep/2 bytes of a stream, and how many bytes came in all."""

    def __init__(self, keep, allowance=None):
        self.half = max(0, keep // 2)
        self.keep = 2 * self.half
        self.allowance = allowance
        self.head = bytearray()
        self.tail = collections.deque()
        self.tail_bytes = 0
        self.total = 0

    def feed(self, data):
        """Take data; the part of it that belongs to the head (written at once by CappedLog)."""
        self.total += len(data)
        room = self.half - len(self.head)
        to_head = data[:max(0, room)]
        self.head += to_head
        rest = data[len(to_head):]
        if rest and self.half:
            self.tail.append(bytes(rest))
            self.tail_bytes += len(rest)
            while self.tail_bytes - len(self.tail[0]) >= self.half:
                self.tail_bytes -= len(self.tail.popleft())
        return bytes(to_head)

    @property
    def cut(self):
        return max(0, self.total - len(self.head) - min(self.tail_bytes, self.half))

    def tail_bytes_kept(self):
        tail = b''.join(self.tail)
        return tail[len(tail) - self.half:] if len(tail) > self.half else tail

    def rest(self):
        """What follows the head: the cut line (if any) and the tail."""
        marker = cut_line(self.cut, self.keep, self.allowance).encode() if self.cut else b''
        return marker + self.tail_bytes_kept()

    def text(self):
        return (bytes(self.head) + self.rest()).decode(errors='replace')


def pump(fd, cap, sink=None):
    """Read fd to its end into cap; what goes to the head is also written to sink (a file)."""
    while True:
        try:
            data = os.read(fd, READ_CHUNK)
        except InterruptedError:
            continue
        except OSError:
            break
        if not data:
            break
        head = cap.feed(data)
        if head and sink is not None:
            try:
                sink.write(head)
                sink.flush()
            except (OSError, ValueError):     # closed by a caller that waited long enough
                sink = None


class CappedLog:
    """A log file fed through a pipe: give it to a child as its stdout (it has fileno()), call
    started(), and close() once the child has ended.

    The head is in the file as it comes (so that it can be read while the
    processes run); the cut line and the tail follow when the pipe ends. name
    and tell() are the file's and where this log begins in it, as for a file
    opened to append. Appended to, the file holds keep bytes (and a cut line
    for each start) however often a launch is started again into it: what
    earlier starts wrote counts against this one's allowance.
    """

    def __init__(self, path, keep, mode='ab'):
        self.path = self.name = path
        self.file = open(path, mode)
        self.start = self.file.tell()
        self.cap = LogCap(max(0, keep - self.start), allowance=keep)
        read_end, self.fd = os.pipe()
        self.thread = threading.Thread(target=self._run, args=(read_end,), daemon=True)
        self.thread.start()

    def _run(self, read_end):
        try:
            pump(read_end, self.cap, self.file)
        finally:
            os.close(read_end)

    def fileno(self):
        return self.fd

    def tell(self):
        return self.start

    def started(self):
        """The child has its copy of the write end: drop ours, so the pipe ends with the child."""
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def close(self, wall_timeout=10.0):
        """Wait for the pipe to end (every writer gone), then write the cut line and the tail
        (once: a second close does nothing)."""
        if self.file.closed:
            return self.cap
        self.started()
        self.thread.join(wall_timeout)
        if not self.thread.is_alive():
            self.file.write(self.cap.rest())
        self.file.close()
        return self.cap


@dataclass
class Captured:
    """What run_captured saw: like subprocess.CompletedProcess, with what was cut."""
    args: list
    returncode: int
    stdout: str
    cut: int = 0
    timed_out: bool = False
    wall_s: float = 0.0            # wall seconds it ran


def run_captured(cmd, env=None, cwd=None, timeout=None, keep=2 << 20, on_stop=None):
    """Run cmd with stdout and stderr together, kept to `keep` bytes (head and tail).

    At the timeout, or when the caller is interrupted (KeyboardInterrupt),
    the command's process group is killed and on_stop() is called to end
    whatever it left (a sandbox's cgroup); an interruption is then raised again.
    """
    started = time.monotonic()
    proc = subprocess.Popen(list(cmd), env=env, cwd=cwd, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    cap = LogCap(keep)
    reader = threading.Thread(target=pump, args=(proc.stdout.fileno(), cap), daemon=True)
    reader.start()
    timed_out = False
    try:
        proc.wait(timeout)
    except subprocess.TimeoutExpired:
        timed_out = True
        _stop(proc, on_stop)
    except BaseException:
        _stop(proc, on_stop)
        raise
    finally:
        # Whatever the command left holding the pipe is gone once its sandbox has ended.
        reader.join(10.0)
        if not reader.is_alive():
            proc.stdout.close()
    return Captured(list(cmd), proc.returncode, cap.text(), cap.cut, timed_out,
                    time.monotonic() - started)


def _stop(proc, on_stop):
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    if on_stop is not None:
        on_stop()
    proc.wait()
