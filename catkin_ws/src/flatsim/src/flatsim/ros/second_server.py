"""A second simulator on one master leaves the first alone, as a second gzserver does.

A second gzserver cannot take Gazebo's port: it prints

    [Err] [Master.cc:96] EXCEPTION: Unable to start server[bind: Address already in use].
    There is probably another Gazebo process running.

and exits with status 255 before its ROS node registers, so the first world,
and the launch and master that own it, run on. A second flatsim would instead
register under the first one's node name, and the master would shut the first
one down. So flatsim asks the master first: if a node of its own name is
registered and answers, it says what gzserver says and exits the same way.

No rospy: this runs before the node registers.
"""
import xmlrpc.client

import rosgraph
import rosgraph.names

# gzserver's status when its server cannot start (main returns -1).
EXIT_STATUS = 255
MESSAGE = ('[Err] [flatsim] EXCEPTION: Unable to start server[%s]. '
           'There is probably another Gazebo process running.')
CALLER_ID = '/flatsim_startup_check'
ANSWER_TIMEOUT_S = 2.0


class TimeoutTransport(xmlrpc.client.Transport):
    """XML-RPC over HTTP that gives up after timeout seconds: a node that is registered but
    hangs holds its caller no longer."""

    def __init__(self, timeout):
        super().__init__()
        self.timeout = timeout

    def make_connection(self, host):
        connection = super().make_connection(host)
        connection.timeout = self.timeout
        return connection


def resolved_node_name(default_name, argv, env=None):
    """The name rospy.init_node(default_name) would register, with __name and __ns applied."""
    name = rosgraph.names.load_mappings(argv).get('__name', default_name)
    return rosgraph.names.ns_join(rosgraph.names.get_ros_namespace(env=env, argv=argv), name)


def live_node(name, master_uri, timeout=ANSWER_TIMEOUT_S):
    """(XML-RPC URI, pid) of the node registered on the master as name, if it answers; else None.

    A node that died without unregistering (killed) does not answer, and a
    master that does not answer is left to rospy.init_node to wait for.
    """
    try:
        uri = rosgraph.Master(CALLER_ID, master_uri=master_uri).lookupNode(name)
    except (rosgraph.MasterError, OSError):
        return None
    try:
        code, _message, pid = xmlrpc.client.ServerProxy(
            uri, transport=TimeoutTransport(timeout)).getPid(CALLER_ID)
    except (OSError, xmlrpc.client.Error, ValueError):
        return None
    return (uri, pid) if code == 1 else None


def refusal(name, argv, env=None):
    """The message to exit with when a simulator of this node's name already runs, else None."""
    node = resolved_node_name(name, argv, env)
    master_uri = rosgraph.get_master_uri(env=env, argv=argv)
    running = live_node(node, master_uri)
    if running is None:
        return None
    uri, pid = running
    return MESSAGE % ('%s is already running on the ROS master %s: pid %s at %s'
                      % (node, master_uri, pid, uri))
