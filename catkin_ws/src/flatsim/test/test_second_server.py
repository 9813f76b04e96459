"""flatsim leaves a simulator of its own name alone, as a second gzserver does. No ROS master:
a small XML-RPC server plays the master and the running node."""
import socket
import threading
from xmlrpc.server import SimpleXMLRPCServer

import pytest

from flatsim.ros import second_server


@pytest.mark.parametrize('argv, env, expected', [
    (['simulator'], {}, '/flatsim'),
    (['simulator', '__name:=gazebo'], {}, '/gazebo'),
    (['simulator', '__ns:=/robot1'], {}, '/robot1/flatsim'),
    (['simulator'], {'ROS_NAMESPACE': '/robot2'}, '/robot2/flatsim'),
])
def test_the_name_checked_is_the_one_the_node_would_register(argv, env, expected):
    assert second_server.resolved_node_name('flatsim', argv, env) == expected


def closed_port_uri():
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return 'http://127.0.0.1:%d/' % sock.getsockname()[1]


@pytest.fixture
def master():
    """An XML-RPC server that answers as the master and as the one node registered with it."""
    server = SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False, allow_none=True)
    uri = 'http://127.0.0.1:%d/' % server.server_address[1]
    registered = {}

    def lookup_node(_caller, name):
        if name in registered:
            return 1, 'node api', registered[name]
        return -1, 'unknown node [%s]' % name, ''
    server.register_function(lookup_node, 'lookupNode')
    server.register_function(lambda _caller: (1, '', 4242), 'getPid')
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield uri, registered
    server.shutdown()
    server.server_close()


def test_a_simulator_that_answers_under_this_name_is_refused_with_gazebos_words(master):
    uri, registered = master
    registered['/flatsim'] = uri
    message = second_server.refusal('flatsim', ['simulator', '__master:=%s' % uri], {})
    assert message == (
        '[Err] [flatsim] EXCEPTION: Unable to start server[/flatsim is already running on the ROS '
        'master %s: pid 4242 at %s]. There is probably another Gazebo process running.' % (uri, uri))
    # Another name, or another namespace, is another simulator.
    assert second_server.refusal('flatsim', ['simulator', '__master:=%s' % uri, '__ns:=/r1'], {}) is None
    assert second_server.refusal('flatsim', ['simulator', '__master:=%s' % uri, '__name:=sim2'], {}) is None


def test_a_registered_simulator_that_no_longer_answers_is_replaced(master):
    uri, registered = master
    registered['/flatsim'] = closed_port_uri()       # killed: registered, but nobody listens
    assert second_server.refusal('flatsim', ['simulator', '__master:=%s' % uri], {}) is None


def test_without_a_master_the_check_leaves_the_waiting_to_rospy():
    assert second_server.live_node('/flatsim', closed_port_uri()) is None
