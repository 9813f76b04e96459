"""The grader's calls to what a submission serves, each bounded in time and size.

A node of the submission answers when and how it likes: one byte every few
seconds, or a header that says it is a gigabyte long. A socket's timeout
bounds each wait for the next bytes, not the whole answer, so every call here
has a deadline for the whole of it (Deadline), and reads no more than it
expects: a connection header of at most HEADER_LIMIT, a service's answer of at
most ANSWER_LIMIT.

  service_headers(uri, service)            the TCPROS header a service answers a probe with
  call_service(uri, service, srv, request) one call of a service (ROS's TCPROS protocol)
  node_proxy(uri)                          an XML-RPC proxy to a node whose every call is bounded

Pure: sockets and ROS's wire format only (rosgraph.network), no rospy.
"""
import http.client
import io
import socket
import struct
import time
import xmlrpc.client
from xml.parsers.expat import ExpatError

from rosgraph.network import ROSHandshakeException, decode_ros_handshake_header, encode_ros_handshake_header

# Wall seconds a probe of a service's header may take, connection to last byte.
HEADER_PROBE_S = 5.0
# A real header is a few hundred bytes (the md5, the type and, for a message, its definition).
HEADER_LIMIT = 64 << 10
# DriveToTarget's answer is a short string; anything larger is not an answer the grader reads.
ANSWER_LIMIT = 64 << 10
# Wall seconds one call of a node's XML-RPC interface may take, connection to last byte.
NODE_CALL_S = 2.0
# What of a node's XML-RPC answer the grader reads: its bus information for a few topics.
NODE_ANSWER_LIMIT = 1 << 20
CALLER_ID = '/grade_probe'


class ProbeError(Exception):
    """What the service or node did instead of answering in time, in words for the report."""


class Deadline:
    def __init__(self, seconds):
        self.seconds = seconds
        self.at = time.monotonic() + seconds

    def left(self):
        """Seconds left; socket.timeout when none are, as a socket's own timeout would say."""
        left = self.at - time.monotonic()
        if left <= 0:
            raise socket.timeout('timed out')
        return left


class DeadlineSocket(socket.socket):
    """A socket whose every wait ends at one deadline: the whole exchange's, not each read's."""

    deadline = None

    @classmethod
    def around(cls, sock, deadline):
        wrapped = cls(sock.family, sock.type, sock.proto, fileno=sock.detach())
        wrapped.deadline = deadline
        return wrapped

    def _bounded(self):
        self.settimeout(self.deadline.left())

    def recv(self, *args):
        self._bounded()
        return super().recv(*args)

    def recv_into(self, *args):
        self._bounded()
        return super().recv_into(*args)

    def sendall(self, *args):
        self._bounded()
        return super().sendall(*args)

    def send(self, *args):
        self._bounded()
        return super().send(*args)


def parse_rosrpc(uri):
    """(host, port) of a rosrpc://host:port/ address; ProbeError if it is not one."""
    if not isinstance(uri, str) or not uri.startswith('rosrpc://'):
        raise ProbeError('its address %r is not a rosrpc:// address' % (uri,))
    host, _colon, port = uri[len('rosrpc://'):].rstrip('/').rpartition(':')
    try:
        return host, int(port)
    except ValueError:
        raise ProbeError('its address %r has no port' % uri) from None


def connect(host, port, deadline):
    try:
        sock = socket.create_connection((host, port), timeout=deadline.left())
    except OSError as error:
        raise ProbeError(_why(error, deadline, 'connecting')) from None
    return DeadlineSocket.around(sock, deadline)


def read_exactly(sock, count, deadline, what):
    """count bytes from sock; ProbeError saying how many came if they do not by the deadline."""
    data = io.BytesIO()
    try:
        while data.tell() < count:
            chunk = sock.recv(min(count - data.tell(), 1 << 16))
            if not chunk:
                raise ProbeError('it closed the connection after %d of the %d bytes of %s'
                                 % (data.tell(), count, what))
            data.write(chunk)
    except OSError as error:
        raise ProbeError(_why(error, deadline, 'reading %s' % what,
                              ' (%d of its %d bytes came)' % (data.tell(), count))) from None
    return data.getvalue()


def _why(error, deadline, doing, came=''):
    if isinstance(error, socket.timeout):
        return 'no whole answer within %g s while %s%s' % (deadline.seconds, doing, came)
    return '%s failed: %s%s' % (doing, error.strerror or error, came)


def read_header(sock, deadline, limit=HEADER_LIMIT):
    """A TCPROS connection header, {field: value}; ProbeError if it is too large or too slow."""
    size, = struct.unpack('<I', read_exactly(sock, 4, deadline, 'the length of its header'))
    if size > limit:
        raise ProbeError('its header says it is %d bytes long, more than the %d the grader reads'
                         % (size, limit))
    body = read_exactly(sock, size, deadline, 'its header')
    try:
        return decode_ros_handshake_header(struct.pack('<I', size) + body)
    except (ROSHandshakeException, UnicodeDecodeError, struct.error) as error:
        raise ProbeError('its header is not a TCPROS header: %s' % error) from None


def service_headers(uri, service, within=HEADER_PROBE_S):
    """The header a service answers a probe with (as rosservice's get_service_headers asks),
    within `within` wall seconds in all; ProbeError otherwise."""
    deadline = Deadline(within)
    sock = connect(*parse_rosrpc(uri), deadline)
    try:
        try:
            sock.sendall(encode_ros_handshake_header(
                {'probe': '1', 'md5sum': '*', 'callerid': CALLER_ID, 'service': service}))
        except OSError as error:
            raise ProbeError(_why(error, deadline, 'sending the probe')) from None
        return read_header(sock, deadline)
    finally:
        sock.close()


def call_service(uri, service, srv_type, request, within):
    """One call of a service at uri with request (a srv_type request), its response; ProbeError
    when it does not answer as a service does within `within` wall seconds in all."""
    deadline = Deadline(within)
    sock = connect(*parse_rosrpc(uri), deadline)
    try:
        try:
            sock.sendall(encode_ros_handshake_header(
                {'callerid': CALLER_ID, 'service': service, 'md5sum': srv_type._md5sum,
                 'type': srv_type._type, 'persistent': '0'}))
        except OSError as error:
            raise ProbeError(_why(error, deadline, 'sending the connection header')) from None
        header = read_header(sock, deadline)
        if 'error' in header:
            raise ProbeError('it refused the connection: %s' % header['error'][:200])
        body = io.BytesIO()
        request.serialize(body)
        try:
            sock.sendall(struct.pack('<I', body.tell()) + body.getvalue())
        except OSError as error:
            raise ProbeError(_why(error, deadline, 'sending the request')) from None
        ok, size = struct.unpack('<BI', read_exactly(sock, 5, deadline, 'the start of its answer'))
        if size > ANSWER_LIMIT:
            raise ProbeError('its answer says it is %d bytes long, more than the %d the grader '
                             'reads' % (size, ANSWER_LIMIT))
        data = read_exactly(sock, size, deadline, 'its answer')
        if not ok:
            raise ProbeError('service cannot process request: %s'
                             % data.decode('utf-8', errors='replace')[:200])
        response = srv_type._response_class()
        try:
            return response.deserialize(data)
        except Exception as error:  # noqa: BLE001 - genpy raises several kinds on bad bytes
            raise ProbeError('its answer is not a %s response: %s' % (srv_type._type, error)) from None
    finally:
        sock.close()


class _BoundedConnection(http.client.HTTPConnection):
    def __init__(self, host, within):
        self.deadline = Deadline(within)
        super().__init__(host, timeout=within)

    def connect(self):
        super().connect()
        self.sock = DeadlineSocket.around(self.sock, self.deadline)


class BoundedTransport(xmlrpc.client.Transport):
    """An XML-RPC transport whose each call, connection to last byte, ends within `within` s."""

    # A compressed answer could be small on the wire and large once read.
    accept_gzip_encoding = False

    def __init__(self, within):
        super().__init__()
        self.within = within

    def make_connection(self, host):
        # A new connection, and a new deadline, for each call.
        self.close()
        _chost, _headers, _x509 = self.get_host_info(host)
        self._connection = host, _BoundedConnection(_chost, self.within)
        return self._connection[1]

    def parse_response(self, response):
        parser, unmarshaller = self.getparser()
        read = 0
        while True:
            data = response.read(1 << 14)
            if not data:
                break
            read += len(data)
            if read > NODE_ANSWER_LIMIT:
                raise ProbeError('its answer is longer than the %d bytes the grader reads'
                                 % NODE_ANSWER_LIMIT)
            try:
                parser.feed(data)
            except ExpatError as error:
                raise ProbeError('its answer is not XML: %s' % error) from None
        try:
            parser.close()
            return unmarshaller.close()
        except (ExpatError, xmlrpc.client.ResponseError) as error:
            raise ProbeError('its answer is not XML-RPC: %s' % error) from None


def node_proxy(uri, within=NODE_CALL_S):
    """An XML-RPC proxy to a node's API whose each call takes at most `within` wall seconds;
    a slower answer raises OSError (socket.timeout), a longer one ProbeError."""
    return xmlrpc.client.ServerProxy(uri, transport=BoundedTransport(within))
