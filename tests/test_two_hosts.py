"""The chase spread over two hosts, the way ROS 1 spreads over machines.

Two network namespaces joined by a veth pair stand in for two machines:
host A (10.200.0.1) runs the master and the world (flatsim, the robot), host B
(10.200.0.2) runs ball_chaser. Each sets ROS_IP to its own address and
ROS_MASTER_URI to A's master; ROS_HOSTNAME is unset, as docs/course.md's
"Two machines" section says. A client on B unpauses the world and watches the
robot reach the ball, so images, commands and service calls all cross the link.
"""
import os
import shutil
import subprocess
import sys
import time

import pytest

from chase_tools.procs import ProcessGroup

HOST_A, HOST_B = '10.200.0.1', '10.200.0.2'
MASTER_PORT = 11311  # each namespace has its own ports, so the usual one cannot clash
MASTER_URI = 'http://%s:%d' % (HOST_A, MASTER_PORT)
REACH_M = 0.4
CHASE_TIMEOUT_S = 30.0  # sim seconds; the default placement takes about 5

# Runs on host B: wait for both sides, unpause, report when the robot reaches the ball.
CHASE_CLIENT = r'''
import math, sys, time
import rosgraph, rospy
from std_srvs.srv import Empty
from gazebo_msgs.srv import GetModelState

reach, timeout = float(sys.argv[1]), float(sys.argv[2])
master = rosgraph.Master('/two_hosts_check')
deadline = time.monotonic() + 60
while time.monotonic() < deadline:
    try:
        _, subscribers, services = master.getSystemState()
    except OSError:
        time.sleep(0.3)
        continue
    served = {name for name, _ in services}
    watched = {name for name, nodes in subscribers if nodes}
    if {'/gazebo/get_model_state', '/ball_chaser/command_robot'} <= served \
            and '/camera/rgb/image_raw' in watched:
        break
    time.sleep(0.3)
else:
    sys.exit('the world and ball_chaser did not both come up')
rospy.init_node('two_hosts_check', disable_signals=True)
state_proxy = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)
get_state = lambda name: state_proxy(model_name=name)
while not get_state('my_robot').success:
    time.sleep(0.2)
rospy.ServiceProxy('/gazebo/unpause_physics', Empty)()
start = rospy.get_time()
while rospy.get_time() - start < timeout:
    robot, ball = get_state('my_robot').pose.position, get_state('white_ball').pose.position
    gap = math.hypot(robot.x - ball.x, robot.y - ball.y)
    if gap <= reach:
        print('reached %.2f m after %.1f s' % (gap, rospy.get_time() - start), flush=True)
        sys.exit(0)
    time.sleep(0.05)
sys.exit('not reached: %.2f m after %.0f s of sim time' % (gap, timeout))
'''


def _ip(*args):
    return subprocess.run(['ip'] + list(args), capture_output=True, text=True)


@pytest.fixture
def two_hosts():
    """Namespaces (a, b) joined by a veth pair; skipped where they cannot be made."""
    if os.geteuid() != 0:
        pytest.skip('network namespaces need root')
    if shutil.which('ip') is None:
        pytest.skip('network namespaces need iproute2 (the ip command)')
    tag = os.getpid() % 100000
    ns_a, ns_b = 'flatsimA%d' % tag, 'flatsimB%d' % tag
    veth_a, veth_b = 'fsa%d' % tag, 'fsb%d' % tag
    made = []
    try:
        for ns in (ns_a, ns_b):
            added = _ip('netns', 'add', ns)
            if added.returncode != 0:
                pytest.skip('cannot create a network namespace: %s' % added.stderr.strip())
            made.append(ns)
        steps = [
            ('link', 'add', veth_a, 'type', 'veth', 'peer', 'name', veth_b),
            ('link', 'set', veth_a, 'netns', ns_a),
            ('link', 'set', veth_b, 'netns', ns_b),
            ('-n', ns_a, 'addr', 'add', HOST_A + '/24', 'dev', veth_a),
            ('-n', ns_b, 'addr', 'add', HOST_B + '/24', 'dev', veth_b),
            ('-n', ns_a, 'link', 'set', veth_a, 'up'),
            ('-n', ns_b, 'link', 'set', veth_b, 'up'),
            ('-n', ns_a, 'link', 'set', 'lo', 'up'),
            ('-n', ns_b, 'link', 'set', 'lo', 'up'),
        ]
        for step in steps:
            done = _ip(*step)
            if done.returncode != 0:
                pytest.skip('cannot join the namespaces (ip %s): %s' % (' '.join(step), done.stderr.strip()))
        yield ns_a, ns_b
    finally:
        # Deleting a namespace deletes the veth end in it, and with it the pair.
        for ns in made:
            _ip('netns', 'delete', ns)


class Host(ProcessGroup):
    """Processes started in one namespace, with that host's ROS environment."""

    def __init__(self, ns, address, log):
        env = {k: v for k, v in os.environ.items() if k not in ('ROS_HOSTNAME', 'ROS_IP')}
        env.update(ROS_IP=address, ROS_MASTER_URI=MASTER_URI)
        super().__init__(env)
        self.ns = ns
        self.log = log

    def start(self, *cmd):
        return super().start(['ip', 'netns', 'exec', self.ns] + list(cmd), self.log)

    def run(self, *cmd, timeout):
        return subprocess.run(['ip', 'netns', 'exec', self.ns] + list(cmd), env=self.env,
                              capture_output=True, text=True, timeout=timeout)


def _wait_for_master(host, timeout=30.0):
    deadline = time.monotonic() + timeout
    probe = 'import rosgraph, sys; sys.exit(0 if rosgraph.is_master_online() else 1)'
    while time.monotonic() < deadline:
        if host.run(sys.executable, '-c', probe, timeout=10).returncode == 0:
            return True
        time.sleep(0.5)
    return False


@pytest.mark.skipif(shutil.which('roslaunch') is None or 'catkin_ws' not in os.environ.get('ROS_PACKAGE_PATH', ''),
                    reason='needs the built workspace: source env.sh first')
def test_the_chase_works_with_the_world_and_the_chaser_on_different_hosts(two_hosts, tmp_path):
    ns_a, ns_b = two_hosts
    with open(tmp_path / 'host_a.log', 'w') as log_a, open(tmp_path / 'host_b.log', 'w') as log_b:
        host_a, host_b = Host(ns_a, HOST_A, log_a), Host(ns_b, HOST_B, log_b)
        try:
            host_a.start('roslaunch', '-p', str(MASTER_PORT), 'my_robot', 'world.launch', 'gui:=false',
                         'paused:=true', 'real_time_factor:=1')
            assert _wait_for_master(host_b), 'host B cannot reach the master on host A'
            host_b.start('roslaunch', 'ball_chaser', 'ball_chaser.launch')
            chase = host_b.run(sys.executable, '-c', CHASE_CLIENT, str(REACH_M), str(CHASE_TIMEOUT_S),
                               timeout=80)
            assert chase.returncode == 0, '%s\nhost A log: %s\nhost B log: %s' % (
                chase.stderr, tmp_path / 'host_a.log', tmp_path / 'host_b.log')
            assert chase.stdout.startswith('reached')
        finally:
            host_b.stop()
            host_a.stop()
