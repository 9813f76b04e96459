#!/usr/bin/env python3
"""Spawning a robot whose drive plugin flatsim cannot run: flatsim's log names it.

The test listens on /rosout first and spawns the robot itself, so the warning
cannot go by before it listens.
"""
import sys
import threading
import time
import unittest

import rosgraph
import rospy
import rostest
from gazebo_msgs.srv import SpawnModel
from rosgraph_msgs.msg import Log

WAIT_S = 20.0


class UnknownDriveTest(unittest.TestCase):
    def test_the_log_names_the_plugin_and_its_command_topic(self):
        rospy.init_node('rostest_unknown_drive')
        heard = []
        arrived = threading.Event()

        def on_log(msg):
            if 'libmy_four_wheel_steering.so' in msg.msg:
                heard.append(msg)
                arrived.set()

        subscriber = rospy.Subscriber('/rosout', Log, on_log, queue_size=100)
        rospy.wait_for_service('/gazebo/spawn_urdf_model', timeout=WAIT_S)
        spawn = rospy.ServiceProxy('/gazebo/spawn_urdf_model', SpawnModel)
        deadline = time.monotonic() + WAIT_S
        # Connected to every /rosout publisher, flatsim among them; waited in wall time, as with
        # the world running flat out sim time flies.
        master = rosgraph.Master(rospy.get_name())

        def publishers():
            return next((nodes for topic, nodes in master.getSystemState()[0] if topic == '/rosout'), [])
        while '/flatsim' not in publishers() or subscriber.get_num_connections() < len(publishers()):
            self.assertLess(time.monotonic(), deadline, 'never connected to flatsim\'s /rosout')
            time.sleep(0.05)
        response = spawn(model_name='drive_bot', model_xml=rospy.get_param('/robot_description'))
        self.assertTrue(response.success, response.status_message)
        self.assertTrue(arrived.wait(WAIT_S), 'no log line named the plugin')
        self.assertEqual(heard[0].level, Log.WARN)
        self.assertIn('a drive plugin flatsim cannot run (its commands come on steer_cmd)', heard[0].msg)
        self.assertIn('robot drive_bot', heard[0].msg)


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'unknown_drive', UnknownDriveTest, sys.argv)
