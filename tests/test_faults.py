"""Faults during a chase: a node killed, the simulator restarted, sim time sent back,
a subscriber that stops reading.

Each test runs my_robot world.launch and ball_chaser.launch on a master of its
own, with the world paused until ball_chaser is up. Waits count sim time and
are capped in wall time, so a slow machine fails loudly rather than hanging.
Distances are between the robot's base and the ball's centre.
"""
import os
import signal
import time

import pytest

from rosproc import Probe, RosSystem, run_forked, vm_rss_kib, wait_until

REACH_M = 0.4
CHASE_SIM_S = 60.0
WALL_CAP_S = 120.0
COMMAND_SERVICE = '/ball_chaser/command_robot'
CAMERA_TOPIC = '/camera/rgb/image_raw'
# How much closer the robot must get before a fault is injected, so it is mid-chase.
UNDER_WAY_M = 0.3
CMD_TIMEOUT_S = 1.0
# After the watchdog period, process_image's resend interval (cmd_timeout / 2) and braking.
STOP_MARGIN_S = 1.0
STOPPED_SPEED = 0.02


@pytest.fixture
def ros(tmp_path):
    with RosSystem(tmp_path) as system:
        yield system


def start_chase(ros, real_time_factor=0, chaser_args=()):
    """World (paused) and ball_chaser up, process_image watching the camera."""
    ros.launch('world', 'my_robot', 'world.launch', 'gui:=false', 'paused:=true',
               'real_time_factor:=%g' % real_time_factor)
    # The world launch sets /use_sim_time, which ball_chaser's nodes read as they start.
    ros.graph.wait_for_service('/gazebo/unpause_physics')
    start_chaser(ros, chaser_args)


def start_chaser(ros, chaser_args=()):
    ros.launch('chaser', 'ball_chaser', 'ball_chaser.launch', *chaser_args)
    ros.graph.wait_for_service(COMMAND_SERVICE)
    ros.graph.wait_for_node('/process_image')


def speed(probe, model='my_robot'):
    twist = probe.model_state(model).twist
    return (twist.linear.x ** 2 + twist.linear.y ** 2) ** 0.5


def wait_for_robot(probe):
    """The simulator's services come up before spawn_model has put the robot in."""
    deadline = time.monotonic() + WALL_CAP_S
    while True:
        try:
            return probe.model_state('my_robot')
        except RuntimeError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def wait_under_way(probe):
    wait_for_robot(probe)
    start_gap = probe.gap()
    under_way = probe.wait_sim(lambda: probe.gap() < start_gap - UNDER_WAY_M, CHASE_SIM_S, WALL_CAP_S)
    assert under_way, 'the robot never started chasing (%.2f m from the ball)' % probe.gap()


def wait_reached(probe, what):
    reached = probe.wait_sim(lambda: probe.gap() <= REACH_M, CHASE_SIM_S, WALL_CAP_S)
    assert reached, '%s: still %.2f m from the ball after %g s of sim time' % (what, probe.gap(), CHASE_SIM_S)


class CommandCounter:
    """Counts /cmd_vel messages, so a test can tell that drive_bot still publishes."""

    def __init__(self, probe):
        from geometry_msgs.msg import Twist
        self.count = 0
        self._sub = probe.rospy.Subscriber('/cmd_vel', Twist, self._on_twist)

    def _on_twist(self, _msg):
        self.count += 1


def kill_drive_bot_mid_chase(graph):
    probe = Probe(graph.master_uri)
    try:
        probe.call_empty('/gazebo/unpause_physics')
        wait_under_way(probe)
        old_pid = graph.kill_node('/drive_bot', signal.SIGKILL)
        # While drive_bot is down the robot coasts on the last command; pause so the
        # respawned drive_bot, not that command, has to bring the robot to the ball.
        probe.call_empty('/gazebo/pause_physics')
        new_pid = graph.wait_for_node('/drive_bot', wall_timeout=60.0, not_pid=old_pid)
        graph.wait_for_service(COMMAND_SERVICE)
        counter = CommandCounter(probe)
        time.sleep(1.0)
        probe.call_empty('/gazebo/unpause_physics')
        wait_reached(probe, 'after drive_bot was killed')
        assert counter.count > 0, 'the respawned drive_bot never published on /cmd_vel'
        return old_pid, new_pid
    finally:
        probe.close()


def test_drive_bot_killed_mid_chase_is_respawned_and_the_chase_completes(ros):
    start_chase(ros, real_time_factor=1)
    old_pid, new_pid = run_forked(kill_drive_bot_mid_chase, ros.graph)
    assert new_pid != old_pid
    assert ros.alive('chaser') and ros.alive('world')
    assert ros.graph.node_pid('/process_image') is not None


def kill_process_image_mid_chase(graph):
    probe = Probe(graph.master_uri)
    try:
        probe.call_empty('/gazebo/unpause_physics')
        wait_under_way(probe)
        moving_speed = speed(probe)
        killed_at = probe.sim_time()
        graph.kill_node('/process_image', signal.SIGKILL)
        stopped = probe.wait_sim(lambda: speed(probe) < STOPPED_SPEED, 10.0, WALL_CAP_S)
        stopped_at = probe.sim_time()
        gap_at_stop = probe.gap()
        still = probe.wait_sim(lambda: speed(probe) > STOPPED_SPEED, 2.0, WALL_CAP_S)
        return moving_speed, stopped, stopped_at - killed_at, gap_at_stop, still
    finally:
        probe.close()


def test_process_image_killed_with_cmd_timeout_stops_the_robot(ros):
    # Real time, so the nodes' scheduling delays under CPU load stay small in sim time too.
    start_chase(ros, real_time_factor=1, chaser_args=['cmd_timeout:=%g' % CMD_TIMEOUT_S])
    moving_speed, stopped, stop_delay, gap_at_stop, moved_again = run_forked(
        kill_process_image_mid_chase, ros.graph)
    assert moving_speed > 0.1, 'the robot was not moving when process_image was killed'
    assert stopped, 'the robot kept moving after process_image was killed'
    assert stop_delay <= CMD_TIMEOUT_S + STOP_MARGIN_S, \
        'the robot stopped %.2f s of sim time after process_image died' % stop_delay
    # It stopped because the commands stopped, not because it had reached the ball.
    assert gap_at_stop > REACH_M + 0.2
    assert not moved_again
    assert ros.graph.node_pid('/drive_bot') is not None


def chase_under_way(graph):
    """Unpause and wait until the robot has closed in on the ball."""
    probe = Probe(graph.master_uri)
    try:
        probe.call_empty('/gazebo/unpause_physics')
        wait_under_way(probe)
    finally:
        probe.close()


def test_ball_chaser_survives_a_simulator_restart_and_drives_to_the_ball_again(ros):
    start_chase(ros)
    run_forked(chase_under_way, ros.graph)
    chaser_pids = {node: ros.graph.node_pid(node) for node in ('/drive_bot', '/process_image')}
    ros.graph.shutdown_node('/flatsim')
    # flatsim is required="true": the whole world launch ends with it.
    assert ros.wait_exit('world', wall_timeout=60.0), 'the world launch outlived flatsim'
    ros.launch('world', 'my_robot', 'world.launch', 'gui:=false', 'paused:=true',
               'real_time_factor:=0')
    ros.graph.wait_for_service('/gazebo/get_model_state')
    run_forked(chase_under_way, ros.graph)
    assert {node: ros.graph.node_pid(node) for node in chaser_pids} == chaser_pids


def test_in_the_readmes_startup_a_killed_simulator_takes_the_master_and_the_chase_resumes(tmp_path):
    """As docs/course.md starts it: world.launch starts the master itself, ball_chaser joins it."""
    ros = RosSystem(tmp_path)
    try:
        world = ['roslaunch', '-p', str(ros.port), 'my_robot', 'world.launch', 'gui:=false',
                 'paused:=true', 'real_time_factor:=0']
        ros.run('world', world)
        ros.graph.wait_for_service('/gazebo/unpause_physics')
        start_chaser(ros)
        run_forked(chase_under_way, ros.graph)
        chaser_pids = {node: ros.graph.node_pid(node) for node in ('/drive_bot', '/process_image')}
        ros.graph.kill_node('/flatsim', signal.SIGKILL)
        # flatsim is required="true": the launch ends, and the master it started with it.
        assert ros.wait_exit('world', wall_timeout=60.0), 'the world launch outlived flatsim'
        assert not ros.graph.node_uri('/rosout'), 'the master outlived the world launch'
        ros.run('world', world)
        ros.graph.wait_for_service('/gazebo/get_model_state')
        # The chaser's nodes register with the new master by themselves.
        ros.graph.wait_for_service(COMMAND_SERVICE)
        run_forked(chase_under_way, ros.graph)
        assert {node: ros.graph.node_pid(node) for node in chaser_pids} == chaser_pids
    finally:
        ros.stop()


def reset_time_mid_chase(graph):
    probe = Probe(graph.master_uri)
    try:
        probe.call_empty('/gazebo/unpause_physics')
        wait_under_way(probe)
        before = probe.sim_time()
        probe.call_empty('/gazebo/reset_simulation')
        went_back = probe.wait_sim(lambda: probe.sim_time() < before, 5.0, 30.0)
        assert went_back, 'sim time did not go back after reset_simulation'
        wait_reached(probe, 'after reset_simulation')
    finally:
        probe.close()


def test_chase_completes_after_sim_time_jumps_back(ros):
    # cmd_timeout starts drive_bot's watchdog timer, which must live through the jump too.
    # Real time: faster than real time, a loaded machine's process_image falls more than
    # cmd_timeout of sim time behind the camera, and the watchdog rightly stops the robot.
    start_chase(ros, real_time_factor=1, chaser_args=['cmd_timeout:=%g' % CMD_TIMEOUT_S])
    chaser_pids = {node: ros.graph.node_pid(node) for node in ('/drive_bot', '/process_image')}
    run_forked(reset_time_mid_chase, ros.graph)
    assert {node: ros.graph.node_pid(node) for node in chaser_pids} == chaser_pids
    log = ros.log_tail('chaser', chars=200000)
    assert 'Traceback' not in log and 'MovedBackwards' not in log, log[-4000:]


def sim_seconds_passing(graph, wall_s):
    """Sim seconds that pass in wall_s seconds of wall time, by /clock."""
    probe = Probe(graph.master_uri)
    try:
        assert probe.wait_sim(lambda: probe.sim_time() > 0, 1e9, WALL_CAP_S), 'no /clock reached a new node'
        start = probe.sim_time()
        time.sleep(wall_s)
        return probe.sim_time() - start
    finally:
        probe.close()


def subscribers_of(graph, topic):
    _publishers, subscribers, _services = graph.master().getSystemState()
    return dict(subscribers).get(topic, [])


def test_a_frozen_camera_subscriber_never_holds_the_world_back(ros):
    ros.launch('world', 'my_robot', 'world.launch', 'gui:=false', 'real_time_factor:=0')
    ros.graph.wait_for_service('/gazebo/unpause_physics')
    simulator = ros.graph.wait_for_node('/flatsim')
    viewer = ros.run('viewer', ['rostopic', 'hz', CAMERA_TOPIC])
    assert wait_until(lambda: subscribers_of(ros.graph, CAMERA_TOPIC), WALL_CAP_S)
    time.sleep(1.0)  # frames flowing to it
    memory_before = vm_rss_kib(simulator)
    # Stopped, it reads nothing: the frames made for it fill both socket buffers at once.
    os.killpg(viewer.pid, signal.SIGSTOP)
    try:
        passed = run_forked(sim_seconds_passing, ros.graph, 5.0)
        memory_after = vm_rss_kib(simulator)
    finally:
        os.killpg(viewer.pid, signal.SIGCONT)
    assert passed > 3.0, 'only %.2f s of sim time passed in 5 s with a frozen subscriber' % passed
    # At most one whole 1.9 MB frame waits for it besides the one on the wire.
    assert memory_after - memory_before < 64 * 1024, \
        'the simulator grew by %d KiB while the subscriber was frozen' % (memory_after - memory_before)
