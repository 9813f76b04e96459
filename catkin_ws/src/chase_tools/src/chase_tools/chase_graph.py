"""What chase_demo and evaluate share while a launched chase comes up and runs."""
import math
import os

import rospkg
import rospy

from chase_tools.procs import wait_until


def default_world_file():
    """my_robot's chase_house.world, the world the course chase runs in."""
    return os.path.join(rospkg.RosPack().get_path('my_robot'), 'worlds', 'chase_house.world')


def wait_for_service(name, launches, wall_timeout=60.0):
    """True once the service answers; False if a launch dies or the time runs out first."""
    def served():
        try:
            rospy.wait_for_service(name, timeout=1.0)
            return True
        except rospy.ROSException:
            return False
    return wait_until(served, [launches], wall_timeout, poll_s=0.0)


def chaser_ready(master, camera_topic, ignored_subscribers=()):
    """True once drive_bot serves its service and process_image subscribes to the camera.

    ignored_subscribers: other nodes on the camera topic (a throttle, say).
    """
    _, subscribers, services = master.getSystemState()
    return (any(name == '/ball_chaser/command_robot' for name, _ in services)
            and any(name == camera_topic and set(nodes) - set(ignored_subscribers)
                    for name, nodes in subscribers))


def planar_gap(a, b):
    """Distance in the ground plane between two geometry_msgs/Pose."""
    return math.hypot(a.position.x - b.position.x, a.position.y - b.position.y)
