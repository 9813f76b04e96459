"""Register this node again with a master that was restarted.

`roslaunch my_robot world.launch` starts the master itself when none runs,
so when the simulator dies (it is required="true") the launch ends and takes
the master with it. A relaunch starts a new, empty master on the same port,
and rospy nodes that outlived the old one stay unknown to it: nobody finds
their services, and no publisher connects to their subscriptions. roscpp and
rospy do not register again by themselves.

keep_registered() starts a thread that asks the master once a second
whether it knows this node. When a master answers that it does not, the
thread registers every publication, subscription and service of this node
with it again, as rospy does at start, and the node's subscriptions then
connect to the new publishers. Parameters the old master held are not
restored; the nodes read theirs at start.
"""
import threading
import time

import rosgraph
import rospy
from rospy.impl.registration import (
    RegManager, get_registration_listeners, get_service_manager, get_topic_manager)

CHECK_PERIOD_S = 1.0


def keep_registered(period=CHECK_PERIOD_S):
    thread = threading.Thread(target=_watch, args=(period,), name='rejoin_master', daemon=True)
    thread.start()
    return thread


def _watch(period):
    name = rospy.get_name()
    master = rosgraph.Master(name)
    while not rospy.is_shutdown():
        time.sleep(period)   # wall time: sim time stops with the simulator
        try:
            master.lookupNode(name)
            continue
        except rosgraph.MasterError:
            pass             # a master that does not know this node
        except (OSError, rosgraph.MasterException):
            continue         # no master (yet): ask again later
        if rospy.is_shutdown():
            return
        rospy.logwarn('%s: the ROS master does not know this node (it was restarted); '
                      'registering again', name)
        try:
            register_again(master)
        except (OSError, rosgraph.MasterException) as error:
            rospy.logwarn('%s: registering again failed (%s); will retry', name, error)


def register_again(master):
    """Every publication, subscription and service of this process, with master."""
    uri = rospy.core.get_node_uri()
    topics, services = get_topic_manager(), get_service_manager()
    for topic, data_type in topics.get_publications():
        master.registerPublisher(topic, data_type, uri)
    managers = [listener for listener in get_registration_listeners().listeners
                if isinstance(listener, RegManager)]
    for topic, data_type in topics.get_subscriptions():
        publishers = master.registerSubscriber(topic, data_type, uri)
        for manager in managers:
            manager.publisher_update(topic, publishers)
    for service, service_uri in services.get_services():
        master.registerService(service, service_uri, uri)
