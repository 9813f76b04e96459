"""Window > Chase in a real browser, on the project's world with the course robot
(`roslaunch my_robot world.launch gui:=false`): the robot faces the white ball, and the view
shows the ball's pixels per third as the project's process_image counts them in the camera
image on /camera/rgb/image_raw, and the /cmd_vel commands with the node that sent them: a
test node's, then drive_bot's while the project's chaser runs; and the calls to
/ball_chaser/command_robot, as drive_bot logs them, while the studio raises its log level to
DEBUG for the view.
docs/course.md's picture of it:

    STUDIO_SCREENSHOTS=docs python -m pytest tests/test_studio_chase.py

(without STUDIO_SCREENSHOTS it goes to the test's temporary folder)."""
import os
import re
import signal
import time

import numpy as np
from playwright.sync_api import expect

from studio_browser import browser_context, open_page, screenshot, studio_world, wait_for  # noqa: F401
from rosproc import run_forked
from test_studio_chase_rule import process_image_counts

# Ahead of the robot (at the origin, facing +x) and to its left: over the line between the
# left and middle thirds of its camera image.
BALL_AT = (1.2, 0.3)
THIRDS = ('left', 'middle', 'right')


def toggle_chase(page):
    page.get_by_role('button', name='Window', exact=True).click()
    page.get_by_role('menuitemcheckbox', name='Chase').click()


def shown_counts(page):
    panel = page.get_by_role('region', name='Chase')
    texts = [panel.get_by_role('status', name=third + ' third').text_content() for third in THIRDS]
    return [int(text) if text.isdigit() else None for text in texts]


def process_image_counts_of(message):
    """What ball_chaser's functions count in a sensor_msgs/Image (as a dict of fields)."""
    from ball_chaser.detect import image_to_array
    assert message['encoding'] == 'rgb8'
    pixels = image_to_array(message['height'], message['width'], message['encoding'],
                            message['step'], message['data'])
    return process_image_counts(np.asarray(pixels))


def _publish_commands(master_uri, commands):
    """Publish each (linear.x, angular.z) on /cmd_vel as the node /chase_test, 0.4 s apart."""
    os.environ['ROS_MASTER_URI'] = master_uri
    os.environ.setdefault('ROS_HOSTNAME', 'localhost')
    import rospy
    from geometry_msgs.msg import Twist
    rospy.init_node('chase_test', disable_signals=True)
    publisher = rospy.Publisher('/cmd_vel', Twist, queue_size=10)
    deadline = time.monotonic() + 30.0
    while publisher.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    for linear, angular in commands:
        message = Twist()
        message.linear.x, message.angular.z = linear, angular
        publisher.publish(message)
        time.sleep(0.4)
    rospy.signal_shutdown('done')


def run_the_chaser(studio_world):
    """`roslaunch ball_chaser ball_chaser.launch` on the world, unless it runs already."""
    if 'chaser' not in studio_world.ros.procs or not studio_world.ros.alive('chaser'):
        studio_world.ros.launch('chaser', 'ball_chaser', 'ball_chaser.launch')
        studio_world.ros.graph.wait_for_service('/ball_chaser/command_robot')


def rosout_level(studio_world, node='/drive_bot'):
    """The level of a rospy node's `rosout` logger (that of rospy.loginfo and the rest)."""
    loggers = studio_world.call(node + '/get_loggers', 'roscpp/GetLoggers')['loggers']
    return {logger['name']: logger['level'] for logger in loggers}['rosout']


def rosout_listeners(studio_world):
    """The nodes subscribed to /rosout, as the master knows them."""
    import rosgraph
    _, subscribers, _ = rosgraph.Master('/studio_test', master_uri=studio_world.ros.master_uri).getSystemState()
    return dict(subscribers).get('/rosout', [])


def test_the_chase_view_counts_what_process_image_counts(open_page, studio_world, tmp_path):
    placed = studio_world.call('/gazebo/set_model_state', 'gazebo_msgs/SetModelState', {
        'model_state': {'model_name': 'white_ball', 'reference_frame': 'world',
                        'pose': {'position': {'x': BALL_AT[0], 'y': BALL_AT[1], 'z': 0.1},
                                 'orientation': {'w': 1.0}}}})
    assert placed['success'], placed['status_message']
    page = open_page()
    toggle_chase(page)
    panel = page.get_by_role('region', name='Chase')
    expect(panel.get_by_role('img', name='chase view of my_robot::camera1', exact=False)).to_be_visible()
    # The robot stands still and the ball rests: every frame is the same one.
    wait_for(lambda: sum(count or 0 for count in shown_counts(page)) > 0)
    before = shown_counts(page)
    counted = process_image_counts_of(studio_world.message('/camera/rgb/image_raw', 'sensor_msgs/Image'))
    assert counted[0] > 0 and counted[1] > 0
    assert before == counted
    assert shown_counts(page) == counted
    # The lines between the thirds sit where the course's rule cuts the 800 columns.
    lefts = page.evaluate('''() => [...document.querySelectorAll('.chase-panel .third-line')]
        .map((line) => line.style.left)''')
    assert [float(left.rstrip('%')) for left in lefts] == [100 * 267 / 800, 100 * 534 / 800]

    # Commands on /cmd_vel show in the strip with the node that sent them.
    run_forked(_publish_commands, studio_world.ros.master_uri, [(0.1, 0.0), (0.0, -0.3), (0.0, 0.25), (0.0, 0.0)])
    commands = panel.get_by_role('list', name='commands on /cmd_vel, newest first')
    expect(commands.get_by_role('listitem').first).to_contain_text(
        'linear.x 0.00  angular.z 0.00  from /chase_test')
    expect(commands.get_by_role('listitem').nth(1)).to_contain_text(
        'linear.x 0.00  angular.z 0.25  from /chase_test')
    calls = panel.get_by_role('list', name="lines the service's node logged, newest first")
    expect(calls.get_by_role('listitem').first).to_have_text(
        'no node serves /ball_chaser/command_robot: no call to show', timeout=30000)
    # The project's chaser: drive_bot's /cmd_vel, one for each call process_image makes, and
    # the calls as drive_bot logs them.
    run_the_chaser(studio_world)
    expect(commands.get_by_role('listitem').first).to_contain_text('from /drive_bot', timeout=60000)
    expect(calls.get_by_role('listitem').first).to_contain_text('/drive_bot  command_robot: linear_x=',
                                                                  timeout=30000)
    page.wait_for_timeout(700)
    # Tall enough for the whole panel, the calls under the strip included.
    page.set_viewport_size({'width': 1280, 'height': 1040})
    page.wait_for_timeout(300)
    screenshot(page, 'studio_chase.png', tmp_path)

    # Closed, it asks the simulator for nothing.
    toggle_chase(page)
    expect(panel).to_have_count(0)
    hidden = page.locator('.chase-panel')
    shown_at = hidden.get_attribute('data-sim-time')
    page.wait_for_timeout(500)
    assert hidden.get_attribute('data-sim-time') == shown_at
    assert page.errors == []


CALL = re.compile(r'^(?P<t>[0-9.]+) s  /drive_bot  command_robot: linear_x=(?P<linear>\S+) '
                  r'angular_z=(?P<angular>\S+) -> Velocities applied')
COMMAND = re.compile(r'^(?P<t>[0-9.]+) s  linear.x (?P<linear>\S+)  angular.z (?P<angular>\S+)  from /drive_bot')


def matching_call(page):
    """(call line, /cmd_vel line) shown together in the chase view, the call's request numbers
    being those of the command (shown to two decimals), or None."""
    texts = page.evaluate('''() => [".chase-calls", ".chase-commands:not(.chase-calls)"].map(
        (list) => [...document.querySelectorAll(".chase-panel " + list + " li")].map((item) => item.textContent))''')
    calls = [(text, CALL.match(text)) for text in texts[0]]
    commands = [(text, COMMAND.match(text)) for text in texts[1]]
    for call_text, call in calls:
        for command_text, command in commands:
            if call and command and all(
                    abs(float(call[field]) - float(command[field])) < 0.0051 for field in ('linear', 'angular')):
                return call_text, command_text
    return None


def call_marks(page):
    """How many pixels of the strip's top rows are in the colour of a logged line's mark."""
    return page.evaluate('''() => {
        const strip = document.querySelector(".chase-panel .chase-strip");
        const data = strip.getContext("2d").getImageData(0, 0, strip.width, 4).data;
        let found = 0;
        for (let i = 0; i < data.length; i += 4) {
            if (data[i] === 0xc3 && data[i + 1] === 0x9b && data[i + 2] === 0xd3) found++;
        }
        return found;
    }''')


def test_the_strip_shows_drive_bots_calls_and_puts_its_log_level_back(open_page, studio_world):
    run_the_chaser(studio_world)
    # drive_bot logs its calls at DEBUG: nothing of them reaches /rosout while no view is open.
    wait_for(lambda: rosout_level(studio_world) == 'INFO', timeout=30.0)
    assert '/flatsim' not in rosout_listeners(studio_world)
    page = open_page()
    toggle_chase(page)
    panel = page.get_by_role('region', name='Chase')
    calls = panel.get_by_role('list', name="lines the service's node logged, newest first")
    expect(calls.get_by_role('listitem').first).to_contain_text('/drive_bot  command_robot: linear_x=',
                                                                  timeout=30000)
    assert rosout_level(studio_world) == 'DEBUG'
    # A call's request, as drive_bot logged it, is the /cmd_vel it published for it.
    found = []
    wait_for(lambda: found.append(matching_call(page)) or found[-1], timeout=20.0)
    call_text, command_text = found[-1]
    assert '-> Velocities applied: linear_x=' in call_text and 'from /drive_bot' in command_text
    # And each logged line has its mark along the top of the strip.
    assert call_marks(page) > 0
    assert '/flatsim' in rosout_listeners(studio_world)
    # Closed, the view puts drive_bot's level back, and the simulator stops listening.
    toggle_chase(page)
    wait_for(lambda: rosout_level(studio_world) == 'INFO', timeout=30.0)
    wait_for(lambda: '/flatsim' not in rosout_listeners(studio_world))
    assert page.errors == []


def test_the_simulator_stopping_puts_drive_bots_log_level_back(open_page, studio_world):
    """Last in the module: it stops the world's simulator."""
    run_the_chaser(studio_world)
    page = open_page()
    toggle_chase(page)
    wait_for(lambda: rosout_level(studio_world) == 'DEBUG', timeout=30.0)
    # Ctrl-C on `roslaunch my_robot world.launch`, the view still open.
    os.killpg(studio_world.ros.procs['world'].pid, signal.SIGINT)
    assert studio_world.ros.wait_exit('world', wall_timeout=30.0)
    assert studio_world.ros.alive('chaser')
    assert rosout_level(studio_world) == 'INFO'
