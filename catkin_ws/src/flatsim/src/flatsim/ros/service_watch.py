"""What the chase view's ServiceWatch (flatsim.studio.service_watch) asks of ROS, through
standard ROS 1 means only: the master's lookupService and getSystemState, the serving node's
~get_loggers and ~set_logger_level services (roscpp/GetLoggers, roscpp/SetLoggerLevel, which
every rospy and roscpp node serves), and /rosout (rosgraph_msgs/Log). Every call has a
deadline of DEADLINE seconds of wall time.
"""
import threading
import xmlrpc.client

import rosgraph
import rospy
from rosgraph_msgs.msg import Log
from roscpp.srv import GetLoggers, SetLoggerLevel

from flatsim.ros.second_server import TimeoutTransport
from flatsim.studio.chase import LOG_LEVELS

DEADLINE = 2.0


def within(deadline, call, *args):
    """call(*args) on a thread of its own; its result, its exception, or TimeoutError after
    deadline seconds (the thread is left to end by itself: a node that never answers)."""
    outcome = {}

    def run():
        try:
            outcome['value'] = call(*args)
        except BaseException as error:  # noqa: BLE001 - handed back to the caller
            outcome['error'] = error
    thread = threading.Thread(target=run, name='service watch call', daemon=True)
    thread.start()
    thread.join(deadline)
    if thread.is_alive():
        raise TimeoutError('no answer within %g s' % deadline)
    if 'error' in outcome:
        raise outcome['error']
    return outcome['value']


class _Listening:
    def __init__(self, subscriber):
        self.subscriber = subscriber

    def stop(self):
        self.subscriber.unregister()


class RosGraph:
    def __init__(self, deadline=DEADLINE):
        self.deadline = deadline

    def _master(self, method, *args):
        master = xmlrpc.client.ServerProxy(rosgraph.get_master_uri(),
                                           transport=TimeoutTransport(self.deadline))
        code, message, value = getattr(master, method)(rospy.get_caller_id(), *args)
        return code, message, value

    def serving(self, service):
        code, _, uri = self._master('lookupService', service)
        if code != 1:
            return None
        code, message, state = self._master('getSystemState')
        if code != 1:
            raise RuntimeError(message)
        for name, providers in state[2]:
            if name == service and providers:
                return providers[0], uri
        return None

    def loggers(self, node):
        proxy = rospy.ServiceProxy(rosgraph.names.ns_join(node, 'get_loggers'), GetLoggers)
        response = within(self.deadline, proxy)
        return [(logger.name, logger.level) for logger in response.loggers]

    def set_logger_level(self, node, logger, level):
        proxy = rospy.ServiceProxy(rosgraph.names.ns_join(node, 'set_logger_level'), SetLoggerLevel)
        within(self.deadline, proxy, logger, level)

    def listen(self, on_line):
        def received(message):
            on_line(message.name, LOG_LEVELS.get(message.level, str(message.level)), message.msg,
                    message.header.stamp.to_sec())
        return _Listening(rospy.Subscriber('/rosout', Log, received, queue_size=100))
