"""Gazebo's commands as users type them: gazebo WORLD (with and without a ROS master),
gzserver WORLD, gzclient and rosrun gazebo_ros gzclient, and gazebo_ros's
empty_world.launch, whose default gui:=true starts gzclient as gazebo_gui."""
import asyncio
import json
import os
import re
import signal
import stat
import subprocess
import time
import urllib.parse
import urllib.request

import aiohttp
import pytest
import rosgraph

from rosproc import ReadAsItComes, RosSystem, free_port, run_forked, wait_until
from studio_browser import _call_service

from flatsim.studio import address

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# As docs/course.md types it, from the top of the checkout.
WORLD = 'catkin_ws/src/my_robot/worlds/chase_house.world'
ADDRESS = re.compile(r"Gazebo's window \(flatsim studio\) is at (http://127\.0\.0\.1:\d+/\?token=[\w-]+)")
TIMEOUT = 60.0


class Command(ReadAsItComes):
    """A command run as a user runs it in a terminal, its output read as it comes."""

    def __init__(self, argv, env):
        super().__init__(argv, env=env, stdin=subprocess.DEVNULL, cwd=TOP)

    def wait_for(self, pattern, timeout=TIMEOUT):
        found = wait_until(lambda: re.search(pattern, self.output) or (self.proc.poll() is not None
                                                                       and 'exited'), timeout)
        assert found and found != 'exited', 'no %r in:\n%s' % (pattern, self.output[-3000:])
        return found

    def stop(self, sig=signal.SIGTERM, timeout=30.0):
        """Send sig to the command alone (not its group) and return its exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            code = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            raise
        self.reader.join(5.0)
        return code


def environment(tmp_path, master_uri, **extra):
    env = dict(os.environ, ROS_MASTER_URI=master_uri, ROS_HOME=str(tmp_path / 'ros_home'),
               ROS_LOG_DIR=str(tmp_path / 'ros_log'), ROS_HOSTNAME='localhost')
    env.pop('DISPLAY', None)
    env.pop('WAYLAND_DISPLAY', None)
    env.update(extra)
    return env


def master_up(master_uri):
    try:
        rosgraph.Master('/test', master_uri=master_uri).getPid()
    except Exception:  # noqa: BLE001 - no answer at all
        return False
    return True


def world_models(master_uri):
    return run_forked(_call_service, master_uri, '/gazebo/get_world_properties',
                      'gazebo_msgs/GetWorldProperties', {})['model_names']


def test_gazebo_world_without_a_master_starts_roscore_and_stops_it(tmp_path):
    master_uri = 'http://localhost:%d' % free_port()
    gazebo = Command(['gazebo', WORLD], environment(tmp_path, master_uri))
    try:
        gazebo.wait_for(ADDRESS.pattern)
        assert 'no ROS master at %s: starting roscore' % master_uri in gazebo.output
        assert 'no display: open the address above in a browser' in gazebo.output
        models = world_models(master_uri)
        # The world, without any robot.
        assert {'building', 'white_ball', 'table'} <= set(models)
        assert 'my_robot' not in models
        address_files = os.listdir(tmp_path / 'ros_home' / 'studio')
        assert len(address_files) == 1
    finally:
        code = gazebo.stop()
    assert code == 0, gazebo.output[-2000:]
    assert not master_up(master_uri)
    assert os.listdir(tmp_path / 'ros_home' / 'studio') == []
    assert 'Traceback' not in gazebo.output


def test_gazebo_alone_opens_an_empty_world_and_its_window(tmp_path):
    """The course's `gazebo`, then Edit > Model Editor: a world with no model, and its window."""
    master_uri = 'http://localhost:%d' % free_port()
    gazebo = Command(['gazebo'], environment(tmp_path, master_uri))
    try:
        gazebo.wait_for(ADDRESS.pattern)
        assert world_models(master_uri) == []
    finally:
        assert gazebo.stop() == 0, gazebo.output[-2000:]
    assert 'Traceback' not in gazebo.output


def test_gazebo_world_joins_a_running_master_and_leaves_it_running(tmp_path):
    with RosSystem(tmp_path) as ros:
        env = environment(tmp_path, ros.master_uri)
        gazebo = Command(['gazebo', WORLD], env)
        try:
            gazebo.wait_for(ADDRESS.pattern)
            assert 'starting roscore' not in gazebo.output
            assert ros.graph.wait_for_service('/gazebo/spawn_sdf_model', 10.0)
            assert 'white_ball' in world_models(ros.master_uri)
            # One simulator per master, as one gzserver per port.
            second = subprocess.run(['gazebo', WORLD], env=env, capture_output=True, text=True,
                                    timeout=TIMEOUT, cwd=TOP)
            assert second.returncode == 1
            assert 'a simulator already runs on the master at %s' % ros.master_uri in second.stderr
        finally:
            code = gazebo.stop(signal.SIGINT)
        assert code == 0
        assert master_up(ros.master_uri)
        assert ros.graph.service_uri('/gazebo/get_model_state') is None


async def first_message_types(url, count):
    parts = urllib.parse.urlsplit(url)
    base = '%s://%s' % (parts.scheme, parts.netloc)
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(base + '/ws?' + parts.query, headers={'Origin': base}) as socket:
            return [json.loads((await socket.receive(timeout=TIMEOUT)).data)['type'] for _ in range(count)]


def token_of(url):
    (token,) = urllib.parse.parse_qs(urllib.parse.urlsplit(url).query)['token']
    return token


def ros_log_texts(log_dir):
    """{path: text} of every file under the ROS log folder: the nodes' logs and rosout.log."""
    texts = {}
    for folder, _, files in os.walk(log_dir):
        for name in files:
            with open(os.path.join(folder, name), errors='replace') as log:
                texts[os.path.join(folder, name)] = log.read()
    return texts


def test_the_token_never_reaches_rosout_nor_any_ros_log(tmp_path):
    """rospy writes to a node's own log file each line it sends to /rosout, which any node on
    the graph can hear (an echo of /rosout itself misses the lines sent before it connects)."""
    with RosSystem(tmp_path) as ros:
        env = environment(tmp_path, ros.master_uri)
        gazebo = Command(['gzserver', WORLD], env)
        try:
            ros.graph.wait_for_service('/gazebo/get_model_state')
            path = address.address_path(env['ROS_MASTER_URI'], home=env['ROS_HOME'])
            url = wait_until(lambda: (address.read_address(path) or {}).get('url'), TIMEOUT)
            assert url, gazebo.output
            said = "the studio (Gazebo's window) is at %s" % address.without_token(url)
            logs = wait_until(lambda: (lambda texts: texts if any(said in text for text in texts.values())
                                       else None)(ros_log_texts(env['ROS_LOG_DIR'])), TIMEOUT)
            assert logs, 'flatsim never logged %r under %s' % (said, env['ROS_LOG_DIR'])
        finally:
            assert gazebo.stop() == 0
    assert [name for name, text in logs.items() if token_of(url) in text] == []


def test_the_simulator_serves_its_page_while_the_master_starts(tmp_path):
    port = free_port()
    env = environment(tmp_path, 'http://localhost:%d' % port)
    simulator = Command(['rosrun', 'flatsim', 'simulator', '__name:=flatsim',
                         '_world_name:=%s' % os.path.join(TOP, WORLD)], env)
    try:
        path = address.address_path(env['ROS_MASTER_URI'], home=env['ROS_HOME'])
        found = wait_until(lambda: address.read_address(path), TIMEOUT)
        assert found, simulator.output
        assert not master_up(env['ROS_MASTER_URI'])
        with urllib.request.urlopen(found['url'], timeout=TIMEOUT) as page:
            assert page.status == 200
        # The page is greeted with the world once the simulator has it, on the master.
        with RosSystem(tmp_path, port=port, env=env):
            types = asyncio.run(first_message_types(found['url'], 2))
            assert types == ['hello', 'scene']
    finally:
        simulator.stop(signal.SIGINT)


def test_gzserver_serves_the_studio_and_gzclient_prints_its_address(tmp_path):
    with RosSystem(tmp_path) as ros:
        env = environment(tmp_path, ros.master_uri)
        server = Command(['gzserver', WORLD], env)
        try:
            ros.graph.wait_for_service('/gazebo/get_model_state')
            client = Command(['rosrun', 'gazebo_ros', 'gzclient'], env)
            try:
                url = client.wait_for(ADDRESS.pattern).group(1)
                assert 'no display: open the address above in a browser' in client.output
                # gzserver opens no window: the simulator's log names the page, without its
                # token, since that log reaches /rosout, which every node on the graph reads.
                assert 'gzserver: Gazebo\'s window' not in server.output
                assert address.without_token(url) in server.output
                assert token_of(url) not in server.output
                # gzclient stays up, as a window does.
                time.sleep(1.0)
                assert client.proc.poll() is None
            finally:
                assert client.stop() == 0
            plain = Command(['gzclient'], env)
            try:
                assert plain.wait_for(ADDRESS.pattern).group(1) == url
            finally:
                plain.stop(signal.SIGINT)
        finally:
            assert server.stop() == 0


def test_gzclient_opens_the_default_browser_without_the_token_on_its_command_line(tmp_path):
    browser = tmp_path / 'browser'
    opened = tmp_path / 'opened'
    browser.write_text('#!/bin/sh\necho "$@" > %s\n' % opened)
    browser.chmod(0o755)
    with RosSystem(tmp_path) as ros:
        server = Command(['gzserver', WORLD], environment(tmp_path, ros.master_uri))
        try:
            client = Command(['gzclient'], environment(tmp_path, ros.master_uri, DISPLAY=':97',
                                                       BROWSER=str(browser)))
            try:
                url = client.wait_for(ADDRESS.pattern).group(1)
                assert wait_until(lambda: opened.exists() and opened.read_text().strip(), 20.0)
            finally:
                client.stop()
        finally:
            server.stop()
    argument = opened.read_text().strip()
    assert 'token' not in argument
    assert argument.startswith('file://')
    page = argument[len('file://'):]
    assert stat.S_IMODE(os.stat(page).st_mode) == 0o600
    with open(page) as forwarding:
        assert url in forwarding.read()


def test_empty_world_launch_with_the_default_gui_starts_gazebo_gui(tmp_path):
    with RosSystem(tmp_path, env=environment(tmp_path, 'http://localhost:1')) as ros:
        ros.launch('world', 'gazebo_ros', 'empty_world.launch',
                   'world_name:=%s' % os.path.join(TOP, WORLD))
        ros.graph.wait_for_service('/gazebo/get_model_state')
        log = wait_until(lambda: ADDRESS.search(ros.log_tail('world', 20000)) and ros.log_tail('world', 20000),
                         TIMEOUT)
        assert log, ros.log_tail('world')
        assert re.search(r'process\[gazebo_gui-\d+\]: started', log), log[-3000:]
        assert 'gzclient: Gazebo\'s window (flatsim studio) is at' in log


@pytest.mark.parametrize('world, says', [
    ('missing.world', 'gazebo: cannot open the world file missing.world: no such file'),
    ('bad.world', 'gazebo: cannot load the world bad.world: '),
])
def test_a_bad_world_file_is_a_clear_error(tmp_path, world, says):
    (tmp_path / 'bad.world').write_text('<sdf version="1.6"><world name="w"><model')
    master_uri = 'http://localhost:%d' % free_port()
    result = subprocess.run(['gazebo', world], cwd=tmp_path, env=environment(tmp_path, master_uri),
                            capture_output=True, text=True, timeout=TIMEOUT)
    assert result.returncode == 1
    assert says in result.stderr
    assert 'Traceback' not in result.stderr + result.stdout
    assert not master_up(master_uri)
