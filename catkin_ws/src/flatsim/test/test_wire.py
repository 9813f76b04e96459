"""DirectConnection: rospy's queued publishing contract, without a thread switch per message."""
import socket
import threading
import time

import pytest
from rospy.impl.tcpros_base import TransportTerminated

from flatsim.ros.wire import DirectConnection


class FakeTransport:
    """What DirectConnection uses of rospy's TCPROSTransport."""

    def __init__(self, sock):
        self.socket = sock
        self.done = False
        self.stat_bytes = self.stat_num_msg = 0
        self.cleanup = None

    def set_cleanup_callback(self, callback):
        self.cleanup = callback

    def write_data(self, data):
        self.socket.sendall(data)
        self.stat_bytes += len(data)
        self.stat_num_msg += 1

    def close(self):
        self.done = True
        if self.cleanup is not None:
            self.cleanup(self)


@pytest.fixture
def pair():
    publisher_end, subscriber_end = socket.socketpair()
    publisher_end.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 65536)
    yield publisher_end, subscriber_end
    publisher_end.close()
    subscriber_end.close()


def read_exactly(sock, count, timeout=10.0):
    sock.settimeout(timeout)
    data = bytearray()
    while len(data) < count:
        chunk = sock.recv(count - len(data))
        assert chunk, 'the stream ended after %d of %d bytes' % (len(data), count)
        data += chunk
    return bytes(data)


def message(tag, size):
    return bytes([tag]) * size


def test_a_message_the_socket_can_take_goes_out_at_once_without_a_writer_thread(pair):
    publisher_end, subscriber_end = pair
    transport = FakeTransport(publisher_end)
    connection = DirectConnection(transport, queue_size=1)
    for tag in range(5):
        assert connection.write_data(message(tag, 100))
    assert read_exactly(subscriber_end, 500) == b''.join(message(tag, 100) for tag in range(5))
    assert connection._writer is None
    assert (transport.stat_num_msg, transport.stat_bytes) == (5, 500)


def test_a_subscriber_that_does_not_read_never_blocks_the_publisher_and_keeps_the_newest(pair):
    publisher_end, subscriber_end = pair
    connection = DirectConnection(FakeTransport(publisher_end), queue_size=1)
    big = 4 * 1024 * 1024  # far more than both socket buffers hold
    started = time.monotonic()
    for tag in range(1, 6):
        connection.write_data(message(tag, big))
    assert time.monotonic() - started < 2.0, 'the publisher waited for the subscriber'
    # The first message was partly on the wire, so it is sent whole; of the
    # rest, queue_size=1 keeps only the newest. Nothing is cut or interleaved.
    assert read_exactly(subscriber_end, big) == message(1, big)
    assert read_exactly(subscriber_end, big) == message(5, big)
    subscriber_end.setblocking(False)
    time.sleep(0.2)
    with pytest.raises(BlockingIOError):
        subscriber_end.recv(1)


def test_order_is_kept_when_the_writer_thread_takes_over(pair):
    publisher_end, subscriber_end = pair
    connection = DirectConnection(FakeTransport(publisher_end), queue_size=0)
    sizes = [3 * 1024 * 1024, 10, 20, 2 * 1024 * 1024, 5]
    expected = b''.join(message(tag, size) for tag, size in enumerate(sizes))
    received = []
    reader = threading.Thread(target=lambda: received.append(read_exactly(subscriber_end, len(expected))))
    reader.start()
    for tag, size in enumerate(sizes):
        connection.write_data(message(tag, size))
    reader.join(timeout=20.0)
    assert received == [expected]


def test_a_closed_subscriber_ends_the_connection_with_transport_terminated(pair):
    publisher_end, subscriber_end = pair
    transport = FakeTransport(publisher_end)
    connection = DirectConnection(transport, queue_size=1)
    subscriber_end.close()
    with pytest.raises(TransportTerminated):
        connection.write_data(b'x' * 100)
    assert transport.done
    with pytest.raises(TransportTerminated):
        connection.write_data(b'x')


def test_the_writer_thread_ends_when_the_connection_closes(pair):
    publisher_end, _subscriber_end = pair
    transport = FakeTransport(publisher_end)
    connection = DirectConnection(transport, queue_size=1)
    connection.write_data(message(1, 4 * 1024 * 1024))
    writer = connection._writer
    assert writer is not None and writer.is_alive()
    transport.close()
    publisher_end.shutdown(socket.SHUT_RDWR)
    writer.join(timeout=5.0)
    assert not writer.is_alive()
