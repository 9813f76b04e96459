"""rospy.init_node without its tenth-of-a-second naps.

rospy.init_node starts the node's XML-RPC server, has another thread register
it with the master, and checks whether that is done every 0.1 s. The
registration takes a few milliseconds, so every node waited about 0.1 s for
nothing: the simulator and the spawner are on the path from `roslaunch` to
the robot's first camera frame. Here the same wait looks every 5 ms.
"""
import time

import rospy
import rospy.impl.init

REGISTRATION_POLL_S = 0.005


class _PromptTime:
    """The time module as rospy.impl.init sees it, with naps no longer than REGISTRATION_POLL_S."""

    def __getattr__(self, name):
        return getattr(time, name)

    @staticmethod
    def sleep(seconds):
        time.sleep(min(seconds, REGISTRATION_POLL_S))


def init_node(name, **kwargs):
    """rospy.init_node(name, **kwargs), waiting for its registration in short naps."""
    if getattr(rospy.impl.init, 'time', None) is not time:
        # Another rospy than the one this was written against: its own wait, then.
        rospy.init_node(name, **kwargs)
        return
    rospy.impl.init.time = _PromptTime()
    try:
        rospy.init_node(name, **kwargs)
    finally:
        rospy.impl.init.time = time
