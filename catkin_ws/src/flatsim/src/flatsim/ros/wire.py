"""Publishing from the stepping thread straight onto the subscriber's socket.

rospy gives every subscriber of a publisher with a queue_size a
QueuedConnection: each publish() appends to a queue, wakes that
subscriber's writer thread and yields the interpreter to it
(time.sleep(0)). The simulator publishes hundreds of messages per sim
second (/clock, odometry, tf, joint states, scans, frames), so at a
real-time factor of 0 those thread switches cost it more than the
simulation itself.

DirectConnection keeps QueuedConnection's promise, that a slow or stopped
subscriber never blocks the publisher and that at most queue_size messages
wait for it, without the switch: it hands the message to the kernel at
once, without blocking, and only what the socket's buffer cannot take yet
goes to a writer thread, started the first time that happens. Messages keep
their order; a message the kernel has taken in part is never dropped.
"""
import collections
import errno
import socket
import threading

import rospy.topics
from rospy.impl.tcpros_base import TransportTerminated

_CLOSED_BY_PEER = (errno.EPIPE, errno.ECONNRESET)


class DirectConnection:
    """A rospy publisher transport wrapper, in QueuedConnection's place."""

    def __init__(self, connection, queue_size):
        self._connection = connection
        self._queue_size = queue_size
        self._cond = threading.Condition(threading.Lock())
        self._pending = collections.deque()
        self._head_on_wire = False  # the first pending message is partly sent
        self._error = None
        self._writer = None
        connection.set_cleanup_callback(self._on_closed)

    def __getattr__(self, name):
        if name.startswith('__'):
            raise AttributeError(name)
        return getattr(self._connection, name)

    def _on_closed(self, _connection):
        with self._cond:
            self._cond.notify()

    def write_data(self, data):
        failure = None
        with self._cond:
            if self._error is not None:
                error, self._error = self._error, None
                raise error
            if self._pending:
                self._make_room()
                self._queue(data)
            else:
                sent, failure = self._send_now(data)
                if failure is None and sent < len(data):
                    self._head_on_wire = sent > 0
                    self._queue(memoryview(data)[sent:])
        if failure is not None:
            # Outside the lock: closing calls back into _on_closed.
            self._connection.close()
            raise failure
        return True

    def _queue(self, data):
        """Under the lock: leave data to the writer thread, starting it the first time."""
        self._pending.append(data)
        if self._writer is None:
            self._writer = threading.Thread(target=self._write_pending, daemon=True, name='flatsim-wire')
            self._writer.start()
        self._cond.notify()

    def _make_room(self):
        """At most queue_size whole messages wait: the oldest goes, as in QueuedConnection."""
        waiting = len(self._pending) - self._head_on_wire
        if self._queue_size > 0 and waiting >= self._queue_size:
            del self._pending[1 if self._head_on_wire else 0]

    def _send_now(self, data):
        """(bytes the kernel took without waiting, the error that ends the connection or None)."""
        connection = self._connection
        if connection.done or connection.socket is None:
            return 0, TransportTerminated('connection closed')
        try:
            sent = connection.socket.send(data, socket.MSG_DONTWAIT)
        except BlockingIOError:
            return 0, None
        except OSError as error:
            reason = 'closed by the subscriber' if error.errno in _CLOSED_BY_PEER else str(error)
            return 0, TransportTerminated(reason)
        connection.stat_bytes += sent
        if sent == len(data):
            connection.stat_num_msg += 1
        return sent, None

    def _write_pending(self):
        connection = self._connection
        while True:
            with self._cond:
                while not self._pending and not connection.done:
                    self._cond.wait()
                if connection.done:
                    self._pending.clear()
                    self._writer = None
                    return
                data = self._pending[0]
                self._head_on_wire = True
            try:
                # Blocks for as long as the subscriber reads slowly; the stepping thread does not.
                connection.write_data(data)
            except Exception as error:  # noqa: BLE001 - handed to the next write_data, as rospy does
                with self._cond:
                    self._error = error
                    self._pending.clear()
                    self._head_on_wire = False
                    self._writer = None
                return
            with self._cond:
                self._pending.popleft()
                self._head_on_wire = False


def publish_directly():
    """Every publisher this process creates from now on writes through DirectConnection."""
    rospy.topics.QueuedConnection = DirectConnection
