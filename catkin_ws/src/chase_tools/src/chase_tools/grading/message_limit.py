"""The largest TCPROS message a process of the grader's takes.

The grader's own node (session.py) and the grader's simulator, which every node
of the submission reaches over ROS, take no message larger than a camera frame
of the robot's: a publisher that announces 1.5 GB would otherwise grow them by
as much, outside the submission's limits. The simulator runs under
`python -m chase_tools.grading.message_limit RECORD PROGRAM ARGS...`, which
guards it and writes its refusals to RECORD, for the grader's report.
"""
import json
import os
import runpy
import struct
import sys
import threading
import time

from chase_tools.grading.limits import size_text

# The largest message the grader's node takes that is not a camera frame: a model state of a
# thousand models, a scan of tens of thousands of beams. A camera frame may be as large as the
# robot's camera makes one (at most 4 bytes a pixel, whatever its format), and a header more.
MESSAGE_LIMIT = 8 << 20
FRAME_HEADER_BYTES = 64 << 10
BYTES_PER_PIXEL = 4
# Bytes of a refusals record the grader reads.
RECORD_LIMIT = 64 << 10
# Wall seconds the report waits, in all, for the master and the nodes to name who sent what
# was refused: a sender that does not answer is shown by its address.
NAMING_S = 10.0


class MessageLimit:
    """This process takes no TCPROS message larger than `limit` bytes: a connection whose next
    message says it is larger is closed as soon as its length has come, before any more of it
    is read, and the refusal is kept for the report.

    rospy reads a message's 4-byte length, then buffers until the whole message has
    come: a publisher (or a service) that announces 1.5 GB and sends it would grow
    this process by as much. Its protocols' read_messages see the buffer after each
    read of the socket (rospy.impl.tcpros_base.TCPROSTransport.receive_once), which is
    where the length is checked.
    """
    SHOWN = 5

    def __init__(self, limit=MESSAGE_LIMIT, sender=None, record=None):
        self.limit = limit
        # A file (the simulator's, when it runs under run_guarded) that holds the refusals as
        # JSON, written anew at each, for the grader to read.
        self.record = record
        # sender(topic, port): the node that sends on topic from that TCPROS port, or None.
        self.sender = sender or (lambda topic, port: None)
        self.refused = {}               # (what, host:port, declared bytes) -> connections closed
        self.names = {}                 # (what, port) -> the node that sent, once named
        self.naming = []                # the threads that name them
        self.lock = threading.Lock()
        from rospy.impl.tcpros_pubsub import TCPROSSub
        from rospy.impl.tcpros_service import TCPROSServiceClient
        # A subscriber's buffer begins with the length; a service's answer with an ok byte.
        for protocol, start in ((TCPROSSub, 0), (TCPROSServiceClient, 1)):
            self.guard(protocol, start)

    def guard(self, protocol, start):
        if hasattr(protocol, 'unlimited_read_messages'):
            protocol.message_limit = self
            return
        protocol.unlimited_read_messages = protocol.read_messages
        protocol.message_limit = self

        def read_messages(impl, b, msg_queue, sock):
            if b.tell() >= start + 4:
                with b.getbuffer() as view:
                    (size,) = struct.unpack_from('<I', view, start)
                limit = impl.message_limit
                if size > limit.limit:
                    limit.refuse(impl, sock, size)
            return impl.unlimited_read_messages(b, msg_queue, sock)
        protocol.read_messages = read_messages

    def refuse(self, protocol, sock, size):
        """Close the connection at once; which node sent it is asked of the master meanwhile,
        in a thread of its own (notes() waits for it at most NAMING_S)."""
        from rospy.impl.tcpros_base import TransportTerminated
        what = getattr(protocol, 'resolved_name', '?')
        try:
            host, port = sock.getpeername()[:2]
            peer = '%s:%d' % (host, port)
        except (OSError, TypeError, ValueError):
            port, peer = None, '?'
        with self.lock:
            key = (what, peer, size)
            self.refused[key] = self.refused.get(key, 0) + 1
            if port is not None and (what, port) not in self.names:
                self.names[(what, port)] = None
                naming = threading.Thread(target=self.name_sender, args=(what, port), daemon=True)
                self.naming.append(naming)
                naming.start()
            if self.record is not None:
                print('[grader] refused a message of %d bytes on %s from %s' % (size, what, peer),
                      file=sys.stderr, flush=True)
                self.write_record()
        raise TransportTerminated('a message of %d bytes announced on %s, more than the %d the '
                                  'grader takes' % (size, what, self.limit))

    def name_sender(self, what, port):
        node = self.sender(what, port)
        with self.lock:
            self.names[(what, port)] = node

    def shown_peer(self, what, peer):
        """'/node (host:port)' once the sender is named, else 'host:port'."""
        _host, _colon, port = peer.rpartition(':')
        node = self.names.get((what, int(port))) if port.isdigit() else None
        return '%s (%s)' % (node, peer) if node else peer

    def allow_frames(self, width, height):
        """The robot's largest camera frame is width x height: take a frame of that."""
        self.limit = max(MESSAGE_LIMIT, width * height * BYTES_PER_PIXEL + FRAME_HEADER_BYTES)

    def write_record(self):
        shown = sorted(self.refused.items())[:self.SHOWN]
        text = json.dumps({'limit': self.limit, 'refused': [
            [what, peer, size, count] for (what, peer, size), count in shown]})
        temporary = self.record + '.new'
        with open(temporary, 'w') as stream:
            stream.write(text)
        os.replace(temporary, self.record)

    def notes(self):
        deadline = time.monotonic() + NAMING_S
        for naming in list(self.naming):
            naming.join(max(0.0, deadline - time.monotonic()))
        with self.lock:
            refused = sorted(self.refused.items())
            return ['the grader refused a message of %s on %s from %s (%d time%s), larger than the '
                    '%s it takes (the largest frame of the robot\'s camera, or %s for any other '
                    'message): the connection was closed before it was read'
                    % (size_text(size), what, self.shown_peer(what, peer), count,
                       '' if count == 1 else 's', size_text(self.limit), size_text(MESSAGE_LIMIT))
                    for (what, peer, size), count in refused[:self.SHOWN]]


def simulator_notes(record_text, sender):
    """The notes on what the grader's simulator refused: record_text is its RECORD (JSON);
    sender(topic, port) names the node that sent from that port."""
    try:
        record = json.loads(record_text)
        limit, refused = int(record['limit']), record['refused']
        notes = []
        for what, peer, size, count in refused[:MessageLimit.SHOWN]:
            host, _colon, port = str(peer).rpartition(':')
            node = sender(str(what), int(port)) if port.isdigit() else None
            shown = '%s (%s)' % (node, peer) if node else str(peer)
            notes.append('the grader\'s simulator refused a message of %s on %s from %s (%d time%s), '
                         'larger than the %s it takes: the connection was closed before it was read'
                         % (size_text(int(size)), what, shown, int(count), '' if count == 1 else 's',
                            size_text(limit)))
        return notes
    except (ValueError, TypeError, KeyError):
        return ['the grader\'s simulator kept a record of refused messages that could not be read']


def run_guarded(argv):
    """RECORD PROGRAM ARGS...: run the Python program PROGRAM as its own __main__, taking no
    message over MESSAGE_LIMIT, its refusals written to RECORD."""
    record, program = argv[0], argv[1]
    MessageLimit(record=record)
    sys.argv = [program] + argv[2:]
    runpy.run_path(program, run_name='__main__')


if __name__ == '__main__':
    run_guarded(sys.argv[1:])
