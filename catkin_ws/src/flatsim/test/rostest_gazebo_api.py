#!/usr/bin/env python3
"""Gazebo's ROS API as a Gazebo-era script uses it: teleport the ball, read
model and link states, spawn and delete, push with a wrench, change the step,
reset. Answers are gazebo_ros's own: success flags, status messages and
reference-frame rules (ignition's `pose - frame`, velocities turned into the
frame).
"""
import math
import os
import subprocess
import sys
import time
import unittest

import rosgraph
import rospy
import rostest
from gazebo_msgs.msg import LinkStates, ModelState, ModelStates
from gazebo_msgs.srv import (ApplyBodyWrench, DeleteModel, GetLinkState, GetModelProperties,
                             GetModelState, GetPhysicsProperties, GetWorldProperties,
                             SetModelConfiguration, SetModelState, SetPhysicsProperties,
                             SpawnModel)
from geometry_msgs.msg import Point, Pose, Quaternion, Twist, Vector3, Wrench
from roslib.packages import find_node
from std_srvs.srv import Empty

from flatsim.loading.urdf_robot import expand_xacro

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rostest_support import Latest, wait_sim, wait_until, yaw_of  # noqa: E402

ROBOT, BALL = 'my_robot', 'white_ball'
ARM_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'simple_arm')
BALL_SDF = ('<?xml version="1.0"?><sdf version="1.6"><model name="anything"><link name="link">'
            '<collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry>'
            '</collision></link></model></sdf>')


def pose(x, y, z=0.0, yaw=0.0):
    return Pose(position=Point(x, y, z),
                orientation=Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)))


def gazebo(name, kind):
    rospy.wait_for_service('/gazebo/' + name, timeout=30.0)
    return rospy.ServiceProxy('/gazebo/' + name, kind)


class GazeboApiTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_gazebo_api')
        cls.get_state = gazebo('get_model_state', GetModelState)
        cls.set_state = gazebo('set_model_state', SetModelState)
        cls.pause = gazebo('pause_physics', Empty)
        cls.unpause = gazebo('unpause_physics', Empty)
        wait_until(lambda: cls.get_state(model_name=ROBOT).success, 'the robot spawned', sim_timeout=None)

    def setUp(self):
        self.pause()
        gazebo('reset_world', Empty)()

    def tearDown(self):
        self.unpause()

    def place(self, name, x, y, z=0.0, yaw=0.0, frame=''):
        response = self.set_state(ModelState(name, pose(x, y, z, yaw), Twist(), frame))
        self.assertTrue(response.success, response.status_message)
        self.assertEqual(response.status_message, 'SetModelState: set model state done')

    def test_model_states_and_world_properties_list_every_model_in_world_order(self):
        self.place(BALL, 1.5, -1.0, 0.1)
        # As in Gazebo, the states go out as the world steps, so not while paused.
        self.unpause()
        states = rospy.wait_for_message('/gazebo/model_states', ModelStates, timeout=20.0)
        world = gazebo('get_world_properties', GetWorldProperties)()
        self.assertTrue(world.success)
        self.assertEqual(world.status_message, 'GetWorldProperties: got properties')
        self.assertEqual(states.name, world.model_names)
        self.assertEqual(states.name[-1], ROBOT)
        ball = states.pose[states.name.index(BALL)]
        self.assertAlmostEqual(ball.position.x, 1.5, delta=0.01)
        self.assertAlmostEqual(ball.position.y, -1.0, delta=0.01)

    def test_states_relative_to_an_entity_follow_ignition(self):
        # Robot at (1, 1) facing +y; ball 2 m in front of it: (0, 2) in its frame.
        self.place(ROBOT, 1.0, 1.0, yaw=math.pi / 2)
        self.place(BALL, 0.0, 2.0, 0.1, frame=ROBOT)
        world = self.get_state(model_name=BALL, relative_entity_name='world')
        self.assertAlmostEqual(world.pose.position.x, -1.0, places=4)
        self.assertAlmostEqual(world.pose.position.y, 1.0, places=4)
        seen = self.get_state(model_name=BALL, relative_entity_name=ROBOT)
        self.assertTrue(seen.success)
        self.assertEqual(seen.status_message, 'GetModelState: got properties')
        self.assertEqual(seen.header.frame_id, ROBOT)
        self.assertAlmostEqual(seen.pose.position.x, 0.0, places=4)
        self.assertAlmostEqual(seen.pose.position.y, 2.0, places=4)
        self.assertAlmostEqual(yaw_of(seen.pose.orientation), 0.0, places=4)
        from_ball = self.get_state(model_name=ROBOT, relative_entity_name=BALL)
        # The ball was placed turned as the robot is: the robot is on its right.
        self.assertAlmostEqual(from_ball.pose.position.x, 0.0, places=4)
        self.assertAlmostEqual(from_ball.pose.position.y, -2.0, places=4)
        # A twist given in the robot's frame is turned into the world's.
        response = self.set_state(ModelState(BALL, pose(0.0, 2.0, 0.1), Twist(linear=Vector3(1, 0, 0)),
                                             ROBOT))
        self.assertTrue(response.success)
        twist = self.get_state(model_name=BALL).twist.linear
        self.assertAlmostEqual(twist.x, 0.0, places=4)
        self.assertAlmostEqual(twist.y, 1.0, places=4)

    def test_unknown_names_get_gazebos_messages(self):
        cases = [
            (self.get_state(model_name='ghost'), 'GetModelState: model does not exist'),
            (self.get_state(model_name=BALL, relative_entity_name='nowhere'),
             'GetModelState: reference relative_entity_name not found, did you forget to scope '
             'the body by model name?'),
            (self.set_state(ModelState('ghost', pose(0, 0), Twist(), '')),
             'SetModelState: model does not exist'),
            (self.set_state(ModelState(BALL, pose(0, 0), Twist(), 'nowhere')),
             'SetModelState: specified reference frame entity does not exist'),
            (gazebo('delete_model', DeleteModel)(model_name='ghost'),
             'DeleteModel: model does not exist'),
            (gazebo('get_model_properties', GetModelProperties)(model_name='ghost'),
             'GetModelProperties: model does not exist'),
            (gazebo('get_link_state', GetLinkState)(link_name='my_robot::chassis'),
             'GetLinkState: link not found, did you forget to scope the link by model name?'),
        ]
        for response, message in cases:
            self.assertFalse(response.success, message)
            self.assertEqual(response.status_message, message)

    def test_links_are_the_bodies_gazebo_makes_of_the_urdf(self):
        props = gazebo('get_model_properties', GetModelProperties)(model_name=ROBOT)
        self.assertTrue(props.success)
        self.assertEqual(props.body_names, ['robot_footprint', 'left_wheel', 'right_wheel'])
        self.assertEqual(sorted(props.joint_names), ['left_wheel_hinge', 'right_wheel_hinge'])
        self.assertFalse(props.is_static)
        self.assertTrue(gazebo('get_model_properties', GetModelProperties)(model_name='building')
                        .is_static)
        self.place(ROBOT, 1.0, 0.0)
        wheel = gazebo('get_link_state', GetLinkState)(link_name='my_robot::left_wheel',
                                                       reference_frame='')
        self.assertTrue(wheel.success)
        self.assertEqual(wheel.status_message, 'GetLinkState: got state')
        self.assertAlmostEqual(wheel.link_state.pose.position.x, 1.0, delta=0.2)
        self.assertGreater(wheel.link_state.pose.position.y, 0.05)
        self.unpause()
        links = rospy.wait_for_message('/gazebo/link_states', LinkStates, timeout=20.0)
        self.assertIn('my_robot::left_wheel', links.name)
        self.assertIn('white_ball::link', links.name)

    def test_spawn_and_delete_with_gazebos_answers(self):
        spawn_sdf = gazebo('spawn_sdf_model', SpawnModel)
        spawn_urdf = gazebo('spawn_urdf_model', SpawnModel)
        answer = spawn_sdf('ball2', BALL_SDF, '', pose(1.0, 0.0, 0.1), ROBOT)
        self.assertTrue(answer.success, answer.status_message)
        self.assertEqual(answer.status_message, 'SpawnModel: Successfully spawned entity')
        robot_x = self.get_state(model_name=ROBOT).pose.position.x
        self.assertAlmostEqual(self.get_state(model_name='ball2').pose.position.x, robot_x + 1.0,
                               places=4)
        again = spawn_sdf('ball2', BALL_SDF, '', pose(2.0, 0.0), '')
        self.assertEqual((again.success, again.status_message),
                         (False, 'SpawnModel: Failure - entity already exists.'))
        self.assertEqual(spawn_sdf('x', 'not xml', '', pose(0, 0), '').status_message,
                         'GazeboRosApiPlugin SpawnModel Failure: input model_xml not SDF or URDF, '
                         'or cannot be converted to Gazebo compatible format.')
        with self.assertRaises(rospy.ServiceException):
            spawn_urdf('ball3', BALL_SDF, '', pose(0, 0), '')
        deleted = gazebo('delete_model', DeleteModel)(model_name='ball2')
        self.assertEqual((deleted.success, deleted.status_message),
                         (True, 'DeleteModel: successfully deleted model'))
        self.assertFalse(self.get_state(model_name='ball2').success)

    def test_spawn_model_tool_skips_unknown_tokens_and_refuses_the_database(self):
        script = find_node('gazebo_ros', 'spawn_model')[0]
        run = lambda args: subprocess.run([script] + args, stdout=subprocess.PIPE,  # noqa: E731
                                          stderr=subprocess.STDOUT, text=True, timeout=60)
        path = '/tmp/rostest_gazebo_api_ball.sdf'
        with open(path, 'w') as handle:
            handle.write(BALL_SDF)
        typo = run(['-sdf', '-file', path, '-model', 'typo_ball', '-x', '-1', '_r', '0.5'])
        self.assertEqual(typo.returncode, 0, typo.stdout)
        self.assertIn('ignoring argument(s) it does not know: _r 0.5', typo.stdout)
        self.assertAlmostEqual(self.get_state(model_name='typo_ball').pose.position.x, -1.0)
        database = run(['-sdf', '-database', 'cafe_table', '-model', 'table2'])
        self.assertEqual(database.returncode, 1)
        self.assertIn('flatsim has no Gazebo model database', database.stdout)
        self.assertNotIn('Traceback', database.stdout + typo.stdout)
        gazebo('delete_model', DeleteModel)(model_name='typo_ball')

    def test_spawn_model_sets_the_joints_of_a_ros_control_robot(self):
        arm = expand_xacro(os.path.join(ARM_DIR, 'urdf', 'simple_arm.urdf.xacro'))
        path = '/tmp/rostest_gazebo_api_arm.urdf'
        with open(path, 'w') as handle:
            handle.write(arm)
        script = find_node('gazebo_ros', 'spawn_model')[0]
        spawned = subprocess.run([script, '-urdf', '-file', path, '-model', 'arm', '-x', '3',
                                  '-J', 'joint_1', '0.5', '-J', 'joint_2', '-0.3'],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                 timeout=60)
        try:
            self.assertEqual(spawned.returncode, 0, spawned.stdout)
            link_state = gazebo('get_link_state', GetLinkState)
            link_1 = link_state(link_name='arm::link_1', reference_frame='arm').link_state.pose
            self.assertAlmostEqual(yaw_of(link_1.orientation), 0.5, places=4)
            configure = gazebo('set_model_configuration', SetModelConfiguration)
            moved = configure('arm', '', ['joint_1'], [-0.7])
            self.assertEqual((moved.success, moved.status_message),
                             (True, 'SetModelConfiguration: success'))
            link_1 = link_state(link_name='arm::link_1', reference_frame='arm').link_state.pose
            self.assertAlmostEqual(yaw_of(link_1.orientation), -0.7, places=4)
            # A diff-drive robot's wheel angles mean nothing on the plane: a clear refusal.
            refused = configure(ROBOT, '', ['left_wheel_hinge'], [1.0])
            self.assertFalse(refused.success)
            self.assertIn('ros_control robots only', refused.status_message)
        finally:
            gazebo('delete_model', DeleteModel)(model_name='arm')

    def test_a_quaternion_of_nan_or_inf_and_a_wrench_that_overflows_are_refused(self):
        self.place(BALL, 0.5, -2.0, 0.1, yaw=0.7)
        for bad in (math.nan, math.inf):
            turned = self.set_state(ModelState(BALL, Pose(position=Point(1.0, -1.0, 0.1),
                                                          orientation=Quaternion(0, 0, bad, 1)),
                                               Twist(), ''))
            self.assertFalse(turned.success)
            self.assertIn('not a quaternion of finite numbers', turned.status_message)
        kept = self.get_state(model_name=BALL)
        self.assertAlmostEqual(kept.pose.position.x, 0.5, places=6)
        self.assertAlmostEqual(yaw_of(kept.pose.orientation), 0.7, places=6)
        overflowing = gazebo('apply_body_wrench', ApplyBodyWrench)(
            body_name='white_ball::link', wrench=Wrench(force=Vector3(1e300, 1e300, 0)),
            reference_point=Point(1e300, -1e300, 0), duration=rospy.Duration(1.0))
        self.assertFalse(overflowing.success)
        self.assertTrue(overflowing.status_message.startswith('ApplyBodyWrench: the wrench overflows'),
                        overflowing.status_message)

    def test_a_wrench_pushes_the_ball_for_its_duration(self):
        self.place(BALL, 0.0, -2.0, 0.1)
        wrench = gazebo('apply_body_wrench', ApplyBodyWrench)
        bad = wrench(body_name=BALL, wrench=Wrench(force=Vector3(1, 0, 0)),
                     duration=rospy.Duration(0.5))
        self.assertEqual((bad.success, bad.status_message),
                         (False, 'ApplyBodyWrench: body does not exist'))
        ok = wrench(body_name='white_ball::link', wrench=Wrench(force=Vector3(2.0, 0, 0)),
                    duration=rospy.Duration(0.5))
        self.assertEqual((ok.success, ok.status_message), (True, ''))
        sim_time = gazebo('get_world_properties', GetWorldProperties)
        start = sim_time().sim_time
        self.unpause()
        wait_sim(0.8)
        self.pause()
        elapsed = sim_time().sim_time - start
        moved = self.get_state(model_name=BALL)
        # 2 N on 0.5 kg for 0.5 s against 0.2 m/s^2 of rolling resistance, then coasting.
        coast = elapsed - 0.5
        self.assertGreater(coast, 0.0)
        self.assertAlmostEqual(moved.twist.linear.x, 1.9 - 0.2 * coast, delta=0.1)
        self.assertAlmostEqual(moved.pose.position.x, 0.475 + 1.9 * coast - 0.1 * coast ** 2,
                               delta=0.1)
        self.assertAlmostEqual(moved.pose.position.y, -2.0, delta=0.02)

    def test_physics_properties_change_the_step_and_the_pace(self):
        get_physics = gazebo('get_physics_properties', GetPhysicsProperties)
        set_physics = gazebo('set_physics_properties', SetPhysicsProperties)
        before = get_physics()
        self.assertTrue(before.success)
        self.assertTrue(before.pause)
        self.assertEqual(before.max_update_rate, 0.0)
        refused = set_physics(time_step=1e300, max_update_rate=0.0, gravity=before.gravity,
                              ode_config=before.ode_config)
        self.assertFalse(refused.success)
        self.assertIn('step size must be between', refused.status_message)
        done = set_physics(time_step=0.001, max_update_rate=0.0, gravity=before.gravity,
                           ode_config=before.ode_config)
        self.assertEqual((done.success, done.status_message), (True, 'physics engine updated'))
        after = get_physics()
        self.assertEqual((after.time_step, after.max_update_rate), (0.001, 0.0))
        start = rospy.get_time()
        self.unpause()
        wait_sim(0.2)
        self.assertGreater(rospy.get_time(), start)
        set_physics(time_step=before.time_step, max_update_rate=0.0, gravity=before.gravity,
                    ode_config=before.ode_config)

    def test_a_static_model_is_moved_by_set_model_state_and_put_back_by_reset_world(self):
        props = gazebo('get_model_properties', GetModelProperties)
        self.assertTrue(props(model_name='crate').is_static)
        start = self.get_state(model_name='crate').pose
        self.place('crate', -1.5, 0.75, 0.3, yaw=0.5)
        moved = self.get_state(model_name='crate').pose
        self.assertAlmostEqual(moved.position.x, -1.5)
        self.assertAlmostEqual(moved.position.y, 0.75)
        self.assertAlmostEqual(moved.position.z, 0.3)
        self.assertAlmostEqual(yaw_of(moved.orientation), 0.5)
        self.assertTrue(props(model_name='crate').is_static)
        gazebo('reset_world', Empty)()
        back = self.get_state(model_name='crate').pose.position
        self.assertAlmostEqual((back.x, back.y, back.z),
                               (start.position.x, start.position.y, start.position.z))

    def test_reset_simulation_sets_time_back_and_reset_world_the_poses(self):
        start = self.get_state(model_name=BALL).pose.position
        self.place(BALL, 2.0, 2.0, 0.1)
        gazebo('reset_world', Empty)()
        back = self.get_state(model_name=BALL).pose.position
        self.assertAlmostEqual((back.x, back.y), (start.x, start.y))
        self.unpause()
        wait_sim(0.5)
        gazebo('reset_simulation', Empty)()
        wait_until(lambda: rospy.get_time() < 0.5, 'sim time going back', sim_timeout=1e9)

    def test_the_simulator_keeps_sim_time_without_reading_its_own_clock(self):
        _, subscribers, _ = rosgraph.Master('/rostest_gazebo_api').getSystemState()[:3]
        clock_readers = dict(subscribers).get('/clock', [])
        self.assertNotIn('/flatsim', clock_readers)
        self.unpause()
        wait_sim(0.5)
        self.pause()
        time.sleep(0.5)  # wall time: the last /clock reaches this node too
        # Stamped with the simulator's own rospy time: the last /clock it sent, not zero.
        stamp = self.get_state(model_name=BALL).header.stamp
        self.assertGreater(stamp.to_sec(), 0.5)
        self.assertEqual(stamp, rospy.get_rostime())


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'gazebo_api', GazeboApiTest)
