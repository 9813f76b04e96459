"""The course's path through the studio, end to end, in a real browser and with HOME in a
temporary folder, as docs/course.md's "Building the course's world in the studio" gives it:

    gazebo worlds/student.world        # a copy of the project's chase_house.world, no robot
        the world's own ball deleted; Edit > Model Editor: my_ball, saved; Insert my_ball
        outside the building; File > Save World over worlds/student.world
    xvfb-run -a roslaunch my_robot world.launch world_file:=.../worlds/student.world
    roslaunch ball_chaser ball_chaser.launch
        in the page at the address gzclient printed: my_ball dragged with the mouse in front
        of the robot, which chases it.
"""
import os
import re
import shutil
import signal

import pytest
from playwright.sync_api import expect

from flatsim.loading.sdf_world import load_world
from rosproc import Probe, RosSystem, run_forked, wait_until
from studio_browser import (browser_context, choose, drop, model_my_ball, new_page,  # noqa: F401
                            save_as, wait_for)
from test_studio import grab_handle
from test_studio_commands import ADDRESS

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROJECT_WORLD = os.path.join(TOP, 'catkin_ws', 'src', 'my_robot', 'worlds', 'chase_house.world')
# North of the house (its walls run from x = -3 to 7 and y = -4 to 4): the robot cannot see it.
OUTSIDE = (2.0, 5.5)
# 1.5 m in front of the robot, which world.launch spawns at the origin facing +x, the floor
# clear between them.
IN_FRONT = (1.5, 0.0)
# The robot's origin to the ball's centre when it has reached it: its bumper touches the ball
# at 0.38 m, and the chaser stops at about 0.4 m.
REACH_M = 0.5
UNSEEN_SIM_S = 5.0
CHASE_SIM_S = 30.0
STARTUP_S = 120.0
WALL_CAP_S = 240.0


# What my_robot/rviz/my_robot.rviz displays: the lidar, the camera, the odometry and the world.
RVIZ_TOPICS = {'/scan', '/camera/rgb/image_raw', '/odom', '/flatsim/world_markers'}


def subscribed_topics(ros, node):
    _publishers, subscribers, _services = ros.graph.master().getSystemState()
    return {topic for topic, nodes in subscribers if node in nodes}


def printed_address(ros, name):
    found = ADDRESS.search(ros.log_tail(name, 1 << 20))
    return found and found.group(1)


def delete(page, model):
    models = page.get_by_role('list', name='Models')
    models.get_by_role('button', name=model, exact=True).click()
    page.locator('#view').focus()
    page.keyboard.press('Delete')
    expect(models.get_by_role('button', name=model, exact=True)).to_have_count(0)


def drag_to(page, model, x, y):
    """Drag the model's translation handle with the mouse until the page has it at (x, y)."""
    grabbed = grab_handle(page, model)
    # grab_handle leaves the mouse down, moved (60, 30) from where it grabbed.
    mouse = [grabbed['x'] + 60, grabbed['y'] + 30]
    for _ in range(4):
        here, there = page.evaluate('''([name, x, y]) => {
            const view = window.studio.view;
            const at = view.models.get(name).group.position;
            return [view.screenPointOf(at), view.screenPointOf(at.clone().setX(x).setY(y))]; }''',
                                    [model, x, y])
        mouse = [mouse[0] + there['x'] - here['x'], mouse[1] + there['y'] - here['y']]
        page.mouse.move(*mouse, steps=8)
    page.mouse.up()


def unseen_ball_is_not_chased(master_uri):
    """Once the chaser drives (it answers every camera frame), the robot's distance to my_ball
    over UNSEEN_SIM_S of sim time: (at the start, its least, sim seconds watched)."""
    from geometry_msgs.msg import Twist
    probe = Probe(master_uri)
    try:
        probe.rospy.wait_for_message('/cmd_vel', Twist, timeout=STARTUP_S)
        start_time, start = probe.sim_time(), probe.gap('my_robot', 'my_ball')
        gaps = [start]
        probe.wait_sim(lambda: gaps.append(probe.gap('my_robot', 'my_ball')), UNSEEN_SIM_S, WALL_CAP_S)
        return start, min(gaps), probe.sim_time() - start_time
    finally:
        probe.close()


def chase(master_uri):
    """Where my_ball is, and the sim seconds the robot takes to reach it (None if it does not
    within CHASE_SIM_S; 0.0 when it had reached it by the time this process asked) with the
    distance then."""
    probe = Probe(master_uri)
    try:
        ball = probe.model_state('my_ball').pose.position
        start = probe.sim_time()
        reached = probe.wait_sim(lambda: probe.gap('my_robot', 'my_ball') <= REACH_M, CHASE_SIM_S,
                                 WALL_CAP_S)
        took = probe.sim_time() - start if reached else None
        return (ball.x, ball.y), took, probe.gap('my_robot', 'my_ball')
    finally:
        probe.close()


def test_my_ball_built_inserted_and_saved_in_the_studio_is_chased_once_dragged_in_view(
        tmp_path, browser_context):
    if shutil.which('xvfb-run') is None:
        pytest.skip('needs Xvfb (./setup.sh installs it) for rviz')
    home = tmp_path / 'home'
    home.mkdir()
    world = tmp_path / 'worlds' / 'student.world'
    world.parent.mkdir()
    shutil.copy(PROJECT_WORLD, world)
    env = dict(os.environ, HOME=str(home), ROS_HOME=str(tmp_path / 'ros_home'),
               # gzclient opens the page in the default browser when there is a display; this
               # test opens it in its own, so the default is a command that does nothing.
               BROWSER='true')
    env.pop('DISPLAY', None)
    env.pop('WAYLAND_DISPLAY', None)
    # Not entered: gazebo and roslaunch start the master themselves, as they do for a student.
    ros = RosSystem(tmp_path, env=env)
    try:
        ros.run('gazebo', ['gazebo', str(world)])
        page = new_page(browser_context, wait_for(lambda: printed_address(ros, 'gazebo'), STARTUP_S))
        # The world's own ball goes, so that my_ball is the only ball, the one the robot chases.
        delete(page, 'white_ball')
        model_my_ball(page)
        expect(save_as(page, 'my_ball')).to_have_count(0)
        assert sorted(os.listdir(home / '.gazebo' / 'models' / 'my_ball')) == ['model.config', 'model.sdf']
        # Exit puts my_ball where the editor had it, in the house; it goes outside instead.
        choose(page, 'File', 'Exit Model Editor')
        delete(page, 'my_ball')
        page.get_by_role('tab', name='Insert').click()
        page.get_by_role('list', name=str(home / '.gazebo' / 'models')).get_by_role(
            'button', name='my_ball').click()
        drop(page, *OUTSIDE)
        expect(page.get_by_role('list', name='Models').get_by_role('button', name='my_ball')).to_have_count(1)
        page.locator('#view').focus()
        page.keyboard.press('Control+s')
        expect(page.get_by_role('status', name='Messages')).to_contain_text('Saved the world in %s' % world)
        assert page.errors == []
        page.close()
        ros.procs['gazebo'].send_signal(signal.SIGINT)
        assert ros.wait_exit('gazebo'), ros.log_tail('gazebo')
        saved = {model.name: model.pose for model in load_world(str(world)).models}
        assert 'white_ball' not in saved
        assert (saved['my_ball'].x, saved['my_ball'].y) == pytest.approx(OUTSIDE, abs=0.05)

        ros.run('world', ['xvfb-run', '-a', 'roslaunch', '-p', str(ros.port), 'my_robot', 'world.launch',
                          'world_file:=%s' % world])
        url = wait_for(lambda: printed_address(ros, 'world'), STARTUP_S)
        ros.graph.wait_for_service('/gazebo/get_model_state')
        ros.run('chaser', ['roslaunch', 'ball_chaser', 'ball_chaser.launch'])
        page = new_page(browser_context, url)
        expect(page.get_by_role('list', name='Models').get_by_role('button', name='my_robot')).to_have_count(
            1, timeout=STARTUP_S * 1000)
        # world.launch's gui:=true opened rviz with the project's config: it shows the sensors.
        assert wait_until(lambda: RVIZ_TOPICS <= subscribed_topics(ros, '/rviz'), STARTUP_S, interval=0.2), (
            subscribed_topics(ros, '/rviz'), ros.log_tail('world', 3000))
        start, least, watched = run_forked(unseen_ball_is_not_chased, ros.master_uri)
        assert watched >= UNSEEN_SIM_S and least > start - 0.1, (start, least, watched)

        drag_to(page, 'my_ball', *IN_FRONT)
        ball, took, gap = run_forked(chase, ros.master_uri)
        assert ball == pytest.approx(IN_FRONT, abs=0.25)
        assert took is not None, 'the robot is still %.2f m from my_ball after %g s of sim time' % (
            gap, CHASE_SIM_S)
        assert page.errors == []
        # world.launch's gui:=true opened Gazebo's window (gzclient) too.
        log = ros.log_tail('world', 1 << 20)
        assert re.search(r'process\[gazebo_gui-\d+\]: started', log), log[-3000:]
    finally:
        ros.stop()
