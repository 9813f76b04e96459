"""The course's own simple_arm, as a student has it: a package in the course's
shape (tests/fixtures/course_simple_arm: C++ nodes, a CMakeLists that finds
controller_manager, the course's launch files, URDF and world), built with
catkin_make in an overlay on this workspace and driven through lesson 3 with
the lesson's commands.

The launch is the package's own robot_spawn.launch; the only change is the
simulator's real-time factor, set to 0 (as fast as possible) by a wrapper,
since the nodes and the lesson's waits all run on sim time.
"""
import math
import os
import subprocess
import time

import pytest

from course_blocks import FIXTURE, arm_camera, front_glyph
from flatsim.loading.stand_ins import PIXEL_FONT
from overlay import Overlay
from rosproc import Probe, RosSystem, run_forked, wait_until

NODES = ('simple_mover', 'arm_mover', 'look_away')
FAST_LAUNCH = '''<launch>
  <include file="$(find simple_arm)/launch/robot_spawn.launch"/>
  <param name="/flatsim/real_time_factor" value="0"/>
</launch>
'''
CLAMP_WARNING = 'j2 is out of bounds, valid range (0.00,1.00), clamping to: 1.00'
# Joint 2 holds link_2 (1 kg, centre 0.375 m out) with p = 100 and no integral
# action: it rests past its goal by m g l sin(angle) / p.
SAG = 1.0 * 9.81 * 0.375 / 100.0
WALL_TIMEOUT_S = 120.0


@pytest.fixture(scope='module')
def course_workspace(tmp_path_factory):
    workspace = Overlay(tmp_path_factory.mktemp('course_ws'))
    workspace.add(FIXTURE, name='simple_arm')
    result = workspace.build()
    assert result.returncode == 0, result.stdout[-6000:]
    return workspace


def test_catkin_make_builds_the_course_nodes_against_the_stand_ins(course_workspace):
    devel = os.path.join(course_workspace.root, 'devel', 'lib', 'simple_arm')
    for node in NODES:
        assert os.access(os.path.join(devel, node), os.X_OK), node
    # The overlay's simple_arm shadows this workspace's own, as sourcing devel/setup.bash promises.
    found = subprocess.run(['rospack', 'find', 'simple_arm'], env=course_workspace.env(),
                           stdout=subprocess.PIPE, text=True, check=True).stdout.strip()
    assert found == os.path.join(course_workspace.src, 'simple_arm')


def test_lesson_three_with_the_course_nodes(course_workspace, tmp_path):
    launch_file = tmp_path / 'lesson.launch'
    launch_file.write_text(FAST_LAUNCH)
    with RosSystem(tmp_path, env=course_workspace.env()) as ros:
        ros.launch('arm', str(launch_file))
        try:
            run_forked(follow_lesson_three, ros.graph, ros.env)
        except Exception as error:  # noqa: BLE001 - whatever failed, the launch output says why
            raise AssertionError('%s\n--- launch output ---\n%s' % (error, ros.log_tail('arm'))) from None
        log = ros.log_tail('arm', chars=10 ** 6)
    # arm_mover (C++) warned once: for the clamped call, not after rosparam raised the bound.
    assert log.count(CLAMP_WARNING) == 1, log[-4000:]


def follow_lesson_three(graph, env):
    graph.wait_for_service('/arm_mover/safe_move', WALL_TIMEOUT_S)
    lesson = Lesson(graph.master_uri, env)
    lesson.wait_for_controllers()

    # "The camera is displaying a gray image ... pointing straight up."
    assert lesson.image_is_uniform(), 'the camera should see only the sky at first'

    # The lesson's command, as typed: joint 2 is clamped to max_joint_2_angle 1.0.
    reply = lesson.command(['rosservice', 'call', '/arm_mover/safe_move', 'joint_1: 1.57\njoint_2: 1.57'])
    assert 'msg_feedback: "Joint angles set - j1: 1.570000 , j2: 1.000000"' in reply, reply
    lesson.settle((1.57, 1.0 + SAG * math.sin(1.0)))

    # rosparam set, then the same call brings the blocks into view.
    lesson.command(['rosparam', 'set', '/arm_mover/max_joint_2_angle', '1.57'])
    assert lesson.safe_move(1.57, 1.57) == 'Joint angles set - j1: 1.570000 , j2: 1.570000'
    lesson.assert_sees_the_blocks(lesson.settle((1.57, 1.57 + SAG)))

    # look_away: point the arm at the sky and it turns back to the blocks by itself.
    look_away = subprocess.Popen(['rosrun', 'simple_arm', 'look_away'], env=lesson.env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                 start_new_session=True)
    try:
        wait_until(lambda: graph.node_uri('/look_away'), WALL_TIMEOUT_S)
        lowest = [math.inf]
        lesson.on_joints = lambda position: lowest.__setitem__(0, min(lowest[0], abs(position[1])))
        lesson.safe_move(0.0, 0.0)
        position = lesson.settle((1.57, 1.57 + SAG), sim_timeout=30.0)
        assert lowest[0] < 0.01, 'the arm should have pointed up first (joint 2 reached %.3f)' % lowest[0]
        lesson.assert_sees_the_blocks(position)
    finally:
        os.killpg(look_away.pid, 9)
        look_away.wait()

    # simple_mover swings both joints along the course's sine, on whole seconds.
    mover = subprocess.Popen(['rosrun', 'simple_arm', 'simple_mover'], env=lesson.env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)
    try:
        commands = lesson.commands_until_nonzero('/simple_arm/joint_1_position_controller/command')
    finally:
        os.killpg(mover.pid, 9)
        mover.wait()
    swing = [math.sin(2 * math.pi * 0.1 * k) * math.pi / 2 for k in range(20)]
    assert all(any(abs(c - s) < 1e-9 for s in swing) for c in commands), commands


class Lesson:
    """The student's terminals: rospy for what they watch, the CLI for what they type."""

    def __init__(self, master_uri, env):
        self.env = dict(env)
        probe = Probe(master_uri, name='lesson')
        self.rospy = rospy = probe.rospy
        from sensor_msgs.msg import JointState
        self.joints = None
        self.on_joints = None
        self._safe_move = None
        rospy.Subscriber('/simple_arm/joint_states', JointState, self._on_joints, queue_size=1)

    def _on_joints(self, msg):
        self.joints = msg
        if self.on_joints is not None:
            self.on_joints(msg.position)

    def command(self, argv):
        return subprocess.run(argv, env=self.env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True, timeout=WALL_TIMEOUT_S, check=True).stdout

    def safe_move(self, joint_1, joint_2):
        """Call safe_move from here (quicker than another rosservice process); its feedback."""
        if self._safe_move is None:
            # This workspace's simple_arm has the same GoToPosition.srv; C++ checks the md5sum.
            from simple_arm.srv import GoToPosition
            self._safe_move = self.rospy.ServiceProxy('/arm_mover/safe_move', GoToPosition)
        return self._safe_move(joint_1, joint_2).msg_feedback

    def wait_for_controllers(self):
        from controller_manager_msgs.srv import ListControllers
        service = '/simple_arm/controller_manager/list_controllers'
        self.rospy.wait_for_service(service, timeout=WALL_TIMEOUT_S)
        listing = self.rospy.ServiceProxy(service, ListControllers)
        if not wait_until(lambda: sum(c.state == 'running' for c in listing().controller) == 3,
                          WALL_TIMEOUT_S):
            raise AssertionError('the spawner did not start the three controllers')

    def image(self):
        from sensor_msgs.msg import Image
        msg = self.rospy.wait_for_message('/rgb_camera/image_raw', Image, timeout=WALL_TIMEOUT_S)
        assert (msg.width, msg.height, msg.encoding) == (640, 480, 'rgb8')
        return msg

    def image_is_uniform(self):
        data = bytes(self.image().data)
        return data.count(data[0]) == len(data)

    def settle(self, goal, tolerance=0.02, sim_timeout=15.0):
        """Wait until the joints rest within tolerance of goal; returns their positions."""
        start = self.rospy.get_time()
        deadline = time.monotonic() + WALL_TIMEOUT_S

        def resting():
            msg = self.joints
            return (msg is not None and all(abs(p - g) < tolerance for p, g in zip(msg.position, goal))
                    and all(abs(v) < 0.01 for v in msg.velocity))
        while not resting():
            if self.rospy.get_time() - start > sim_timeout or time.monotonic() > deadline:
                raise AssertionError('joints at %s, not resting at %s' % (
                    self.joints and tuple(self.joints.position), goal))
            time.sleep(0.02)
        return tuple(self.joints.position)

    def assert_sees_the_blocks(self, position):
        msg = self.image()
        data = bytes(msg.data)
        assert data.count(data[0]) != len(data), 'the camera should see more than sky'
        import numpy as np
        image = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.width, 3)
        eye, axes = arm_camera(*position)
        for digit in (1, 2, 3):
            assert front_glyph(image, digit, eye, axes) == PIXEL_FONT[digit], \
                'block %d is not where the camera at %s should see it' % (digit, position)

    def commands_until_nonzero(self, topic):
        from std_msgs.msg import Float64
        seen = []
        deadline = time.monotonic() + WALL_TIMEOUT_S
        while not any(abs(value) > 0.1 for value in seen):
            if time.monotonic() > deadline:
                raise AssertionError('%s carried only %s' % (topic, seen))
            seen.append(self.rospy.wait_for_message(topic, Float64, timeout=WALL_TIMEOUT_S).data)
        return seen
