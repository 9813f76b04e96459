"""Students' own packages in an overlay workspace, built and run after `source env.sh`.

The workspace is built once per session, as a student's ~/catkin_ws: a C++
ball_chaser whose process_image finds the ball with cv_bridge and OpenCV and
whose CMakeLists.txt, like many submissions, has no add_dependencies() on its
generated service header; and a package that builds a Gazebo model plugin.
"""
import pathlib
import subprocess
import textwrap
import time

import pytest

from overlay import Overlay
from rosproc import Probe, RosSystem, run_forked, wait_until

FIXTURES = pathlib.Path(__file__).resolve().parent / 'fixtures'
REACH_M = 0.4
CHASE_SIM_S = 60.0
WALL_CAP_S = 120.0

CV_BRIDGE_NODE = textwrap.dedent('''\
    #!/usr/bin/env python3
    import numpy as np
    from cv_bridge import CvBridge

    bridge = CvBridge()
    rgb = np.zeros((2, 3, 3), np.uint8)
    rgb[0, 1] = (255, 0, 0)
    msg = bridge.cv2_to_imgmsg(rgb, encoding='rgb8')
    bgr = bridge.imgmsg_to_cv2(msg, desired_encoding='bgr8')
    mono = bridge.imgmsg_to_cv2(msg, desired_encoding='mono8')
    print(msg.encoding, msg.width, msg.height, tuple(bgr[0, 1]), mono.shape)
''')


def test_a_python_node_converts_images_with_cv_bridge(tmp_path):
    node = tmp_path / 'process_image.py'
    node.write_text(CV_BRIDGE_NODE)
    node.chmod(0o755)
    result = subprocess.run([str(node)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stderr
    # rgb8 red becomes bgr8 (0, 0, 255): cv_bridge's compiled conversions ran.
    assert result.stdout.split() == ['rgb8', '3', '2', '(0,', '0,', '255)', '(2,', '3)'], result.stdout
    assert 'NumPy' not in result.stderr, result.stderr


def test_image_view_subscribes_to_the_camera_topic(tmp_path):
    topic = '/camera/rgb/image_raw'
    with RosSystem(tmp_path) as ros:
        ros.run('image_view', ['xvfb-run', '-a', 'rosrun', 'image_view', 'image_view',
                               'image:=%s' % topic])

        def subscribed():
            _pubs, subs, _srvs = ros.graph.master().getSystemState()
            return any(name == topic and nodes for name, nodes in subs)

        assert wait_until(subscribed, 60.0), ros.log_tail('image_view')
        assert ros.alive('image_view'), ros.log_tail('image_view')



@pytest.fixture(scope='session')
def student_workspace(tmp_path_factory):
    """(overlay, output of `catkin_make drive_bot process_image`, output of `catkin_make`)."""
    ws = Overlay(tmp_path_factory.mktemp('student') / 'catkin_ws')
    ws.add(FIXTURES / 'ball_chaser_cpp', 'ball_chaser')
    ws.add(FIXTURES / 'gazebo_plugin', 'ball_pusher_plugin')
    # make builds only what these two targets depend on: without a dependency on
    # the generated header they fail on any number of cores, not only on a race.
    nodes_only = ws.build('drive_bot', 'process_image')
    whole = ws.build()
    return ws, nodes_only, whole


def test_nodes_without_add_dependencies_build_after_their_service_header(student_workspace):
    _ws, nodes_only, whole = student_workspace
    assert nodes_only.returncode == 0, nodes_only.stdout[-6000:]
    assert 'No such file or directory' not in nodes_only.stdout
    assert whole.returncode == 0, whole.stdout[-6000:]


def test_a_gazebo_plugin_package_is_skipped_with_its_name(student_workspace):
    ws, nodes_only, whole = student_workspace
    for result in (nodes_only, whole):
        assert ('catkin_make: skipping package ball_pusher_plugin (src/ball_pusher_plugin): '
                'it builds a Gazebo plugin (find_package gazebo_plugins, gazebo)') in result.stdout
        assert 'gazeboConfig.cmake' not in result.stdout
    assert not list(pathlib.Path(ws.root, 'devel').rglob('libball_pusher_plugin.so'))


def wait_for_model(probe, name):
    """flatsim's services come up before spawn_model has put the robot in."""
    deadline = time.monotonic() + WALL_CAP_S
    while True:
        try:
            return probe.model_state(name)
        except RuntimeError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def chase(graph):
    """Unpause the world; (closest gap to the ball within the chase, sim seconds it took)."""
    probe = Probe(graph.master_uri)
    try:
        wait_for_model(probe, 'my_robot')
        start_gap = probe.gap()
        probe.call_empty('/gazebo/unpause_physics')
        start = probe.sim_time()
        reached = probe.wait_sim(lambda: probe.gap() <= REACH_M, CHASE_SIM_S, WALL_CAP_S)
        return start_gap, probe.gap(), probe.sim_time() - start, bool(reached)
    finally:
        probe.close()


def test_a_cpp_node_with_cv_bridge_chases_the_ball(student_workspace, tmp_path):
    ws, _nodes_only, whole = student_workspace
    assert whole.returncode == 0, whole.stdout[-6000:]
    with RosSystem(tmp_path, env=ws.env()) as ros:
        ros.launch('world', 'my_robot', 'world.launch', 'gui:=false', 'paused:=true')
        ros.graph.wait_for_service('/gazebo/unpause_physics')
        ros.launch('chaser', 'ball_chaser', 'ball_chaser.launch')
        ros.graph.wait_for_service('/ball_chaser/command_robot')
        ros.graph.wait_for_node('/process_image')
        start_gap, gap, took, reached = run_forked(chase, ros.graph)
        assert reached, 'still %.2f m from the ball (from %.2f m) after %.0f s of sim time:\n%s' % (
            gap, start_gap, took, ros.log_tail('chaser'))
        # The student's own build ran, not the project's Python ball_chaser.
        assert 'linear_x: 0.500000' in ros.log_tail('chaser', 200000)
