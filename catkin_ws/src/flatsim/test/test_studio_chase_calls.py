"""The chase view's calls to /ball_chaser/command_robot, seen through what the serving node logs,
without a browser or a ROS master: the log of its lines, the rules of the watch, and the watch
itself over a made-up graph (which node serves the service, its loggers, /rosout)."""
import json
import threading
import time

import pytest

from flatsim.studio import chase
from flatsim.studio.chase import LineLog, LoggedLine, ServiceCalls, line_time, loggers_to_raise
from flatsim.studio.hub import Hub
from flatsim.studio.service_watch import COMMAND_SERVICE, ServiceWatch
from flatsim.studio.sim_world import SimWorld
from test_studio_chase_stream import Clock, ask, sim, split  # noqa: F401
from test_studio_hub import Tab


def line(t, node='/drive_bot', text='command_robot: linear_x=0.5 angular_z=0 -> ok', level='DEBUG'):
    return LoggedLine(t, node, level, text)


def test_the_line_log_keeps_the_last_10_s_of_one_nodes_lines():
    log = LineLog()
    log.add(line(1.0, text='old'))
    log.add(line(5.0, text='a'))
    log.add(line(6.0, node='/process_image', text='another node'))
    log.add(line(12.0, text='b'))
    assert [entry.text for entry in log.recent('/drive_bot', 12.0)] == ['a', 'b']
    assert [entry.text for entry in log.recent('/process_image', 12.0)] == ['another node']
    # A line that came just after the camera frame of sim time 11.9 still shows with it.
    assert [entry.text for entry in log.recent('/drive_bot', 11.9)] == ['a', 'b']
    assert log.recent('/drive_bot', 30.0) == []


def test_the_line_log_is_capped_and_forgets_a_run_that_time_went_back_on():
    log = LineLog(limit=3)
    for number in range(5):
        log.add(line(1.0 + number * 0.1, text=str(number)))
    assert [entry.text for entry in log.recent('/drive_bot', 2.0)] == ['2', '3', '4']
    # Reset World: a line before the last one starts a new run.
    log.add(line(0.2, text='new run'))
    assert [entry.text for entry in log.recent('/drive_bot', 0.3)] == ['new run']
    # Time went back and nothing came since: the old run's lines are far ahead of now.
    log.add(line(15.0, text='late'))
    assert log.recent('/drive_bot', 0.5) == []
    log.clear()
    assert log.recent('/drive_bot', 0.5) == []


def test_a_line_is_shown_at_its_stamp_unless_it_is_stale_or_on_wall_time():
    assert line_time(4.2, 4.25) == 4.2
    # /rosout is latched: on subscribing, each node's last line comes again, however old.
    assert line_time(1.0, 20.0) is None
    # A node on wall time (no /use_sim_time) stamps far ahead: it shows when it came.
    assert line_time(1.7e9, 20.0) == 20.0


def test_the_loggers_raised_are_the_users_not_roscpps_own():
    rospy_node = [('rospy', 'INFO'), ('rosout', 'INFO'), ('rospy.topics', 'INFO'), ('rosout_agg', 'INFO')]
    assert loggers_to_raise(rospy_node) == [('rosout', 'INFO')]
    roscpp_node = [('ros', 'info'), ('ros.roscpp', 'info'), ('ros.roscpp.superdebug', 'warn'),
                   ('ros.ball_chaser', 'info'), ('ros.ball_chaser.drive', 'warn')]
    assert loggers_to_raise(roscpp_node) == [('ros.ball_chaser', 'info'), ('ros.ball_chaser.drive', 'warn')]
    # Already at DEBUG: nothing to raise, and nothing to put back.
    assert loggers_to_raise([('rosout', 'DEBUG'), ('ros.pkg', 'debug')]) == []


class Graph:
    """A made-up ROS graph: who serves the service, each node's loggers, and /rosout."""

    def __init__(self):
        self.server = ('/drive_bot', 'rosrpc://localhost:4000')
        self.levels = {'/drive_bot': {'rosout': 'INFO', 'rospy': 'INFO'}}
        self.listeners = []
        self.asked = []
        self.failing = set()     # the methods that fail, as a node that does not answer
        self.lock = threading.Lock()

    def _check(self, method):
        with self.lock:
            self.asked.append(method)
        if method in self.failing:
            raise TimeoutError('no answer within 2 s')

    def serving(self, service):
        self._check('serving')
        assert service == COMMAND_SERVICE
        return self.server

    def loggers(self, node):
        self._check('loggers')
        return sorted(self.levels[node].items())

    def set_logger_level(self, node, logger, level):
        self._check('set_logger_level')
        self.levels[node][logger] = level

    def listen(self, on_line):
        self._check('listen')
        graph = self

        class Listening:
            def stop(self):
                graph.listeners.remove(on_line)
        self.listeners.append(on_line)
        return Listening()

    def log(self, node, text, stamp, level='DEBUG'):
        for listener in list(self.listeners):
            listener(node, level, text, stamp)


def eventually(predicate, timeout=10.0):
    """Wait for the watch's thread; the timeout only ends a test that would hang."""
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, 'the watch did not get there'
        time.sleep(0.01)


@pytest.fixture
def graph():
    return Graph()


@pytest.fixture
def watch(graph):
    sim_time = {'now': 5.0}
    found = ServiceWatch(graph, lambda: sim_time['now'], refresh=0.02)
    found.sim_time = sim_time
    yield found
    found.shutdown()


def test_open_the_watch_keeps_the_serving_nodes_lines_at_debug_and_closed_puts_it_back(watch, graph):
    assert watch.calls(5.0) == ServiceCalls(COMMAND_SERVICE)
    assert graph.asked == []
    watch.open()
    eventually(lambda: graph.levels['/drive_bot']['rosout'] == 'DEBUG')
    # rospy's own logger is not the user's: left as it is.
    assert graph.levels['/drive_bot']['rospy'] == 'INFO'
    # /rosout is latched: a node's last line comes first, when it was logged. Sim time is 15 s.
    watch.sim_time['now'] = 15.0
    graph.log('/drive_bot', 'drive_bot ready', 0.5, level='INFO')
    graph.log('/drive_bot', 'command_robot: linear_x=0.5 angular_z=0 -> Velocities applied', 14.9)
    graph.log('/process_image', 'another node', 14.95)
    calls = watch.calls(15.0)
    assert calls.server == '/drive_bot' and calls.looked_up
    assert [(entry.sim_time, entry.node, entry.level, entry.text) for entry in calls.lines] == [
        (14.9, '/drive_bot', 'DEBUG', 'command_robot: linear_x=0.5 angular_z=0 -> Velocities applied')]
    watch.close()
    eventually(lambda: graph.levels['/drive_bot']['rosout'] == 'INFO')
    assert graph.listeners == []
    assert watch.calls(5.0) == ServiceCalls(COMMAND_SERVICE)
    # Closed, the watch asks the graph nothing.
    asked = len(graph.asked)
    time.sleep(0.1)
    assert len(graph.asked) == asked


def test_the_simulator_stopping_puts_the_levels_back(watch, graph):
    watch.open()
    eventually(lambda: graph.levels['/drive_bot']['rosout'] == 'DEBUG')
    watch.shutdown()
    assert graph.levels['/drive_bot']['rosout'] == 'INFO'
    assert graph.listeners == []
    watch.open()
    time.sleep(0.1)
    assert graph.levels['/drive_bot']['rosout'] == 'INFO'


def test_a_node_serving_the_service_later_or_again_is_found(watch, graph):
    graph.server = None
    watch.open()
    eventually(lambda: watch.calls(5.0).looked_up)
    assert watch.calls(5.0).server is None
    # drive_bot starts after the view opened.
    graph.server = ('/drive_bot', 'rosrpc://localhost:4000')
    eventually(lambda: graph.levels['/drive_bot']['rosout'] == 'DEBUG')
    assert watch.calls(5.0).server == '/drive_bot'
    # drive_bot respawned: the same name at a new address, with its levels at their start.
    graph.levels['/drive_bot']['rosout'] = 'INFO'
    graph.server = ('/drive_bot', 'rosrpc://localhost:4001')
    eventually(lambda: graph.levels['/drive_bot']['rosout'] == 'DEBUG')
    # Another node serves it now: drive_bot's level goes back, the other's up.
    graph.levels['/my_drive_bot'] = {'ros.my_bot': 'info', 'ros.roscpp': 'info'}
    graph.server = ('/my_drive_bot', 'rosrpc://localhost:4002')
    eventually(lambda: graph.levels['/my_drive_bot']['ros.my_bot'] == 'DEBUG')
    assert graph.levels['/drive_bot']['rosout'] == 'INFO'
    assert graph.levels['/my_drive_bot']['ros.roscpp'] == 'info'
    # roscpp makes a logger at its first line: raised at the next look, and put back with the rest.
    graph.levels['/my_drive_bot']['ros.my_bot.drive'] = 'info'
    eventually(lambda: graph.levels['/my_drive_bot']['ros.my_bot.drive'] == 'DEBUG')
    # A level put back by hand meanwhile goes up again, and back to what it was first.
    graph.levels['/my_drive_bot']['ros.my_bot'] = 'warn'
    eventually(lambda: graph.levels['/my_drive_bot']['ros.my_bot'] == 'DEBUG')
    watch.close()
    eventually(lambda: graph.levels['/my_drive_bot']['ros.my_bot'] == 'info')
    assert graph.levels['/my_drive_bot']['ros.my_bot.drive'] == 'info'


def test_a_node_that_does_not_answer_only_means_no_debug_lines(watch, graph):
    graph.failing = {'loggers'}
    watch.open()
    eventually(lambda: watch.calls(5.0).server == '/drive_bot')
    graph.log('/drive_bot', 'Velocities applied: linear_x=0.1', 4.0, level='INFO')
    assert [entry.text for entry in watch.calls(5.0).lines] == ['Velocities applied: linear_x=0.1']
    assert graph.levels['/drive_bot']['rosout'] == 'INFO'
    # The master not answering leaves things as they were.
    graph.failing = {'serving', 'set_logger_level'}
    asked = len(graph.asked)
    eventually(lambda: graph.asked.count('serving') > 2 and len(graph.asked) > asked)
    assert watch.calls(5.0).server == '/drive_bot'
    watch.close()
    eventually(lambda: watch.calls(5.0).server is None)


def test_the_chase_frame_carries_the_calls_while_open(sim, graph):
    world = SimWorld(sim)
    world.service_watch = ServiceWatch(graph, lambda: sim.time, refresh=0.02)
    hub = Hub(world, clock=Clock())
    tab = Tab()
    session = hub.connect(tab)
    ask(hub, session, tab, type='chase', sensor='bot::cam', on=True)
    eventually(lambda: graph.levels['/drive_bot']['rosout'] == 'DEBUG')
    sim.time = 3.0
    graph.log('/drive_bot', 'command_robot: linear_x=0.5 angular_z=0 -> <b>applied</b>', 2.5)
    hub.tick()
    header, _ = split(tab.frames[-1])
    assert header['calls'] == {
        'service': '/ball_chaser/command_robot', 'server': '/drive_bot', 'looked_up': True,
        'marks': [[2.5, 'DEBUG']],
        'lines': [{'t': 2.5, 'node': '/drive_bot', 'level': 'DEBUG',
                   'text': 'command_robot: linear_x=0.5 angular_z=0 -> <b>applied</b>'}]}
    hub.disconnect(session)
    eventually(lambda: graph.levels['/drive_bot']['rosout'] == 'INFO')
    world.service_watch.shutdown()


def test_the_page_gets_every_line_as_a_mark_and_the_newest_as_text():
    lines = tuple(line(1.0 + number * 0.01, text='call %d' % number) for number in range(300))
    lines += (line(4.5, text='x' * 5000, level='ERROR'),)
    shown = ServiceCalls(COMMAND_SERVICE, '/drive_bot', True, lines).as_json()
    assert len(shown['marks']) == 301 and shown['marks'][0] == [1.0, 'DEBUG']
    assert shown['marks'][-1] == [4.5, 'ERROR']
    assert [entry['text'] for entry in shown['lines'][:-1]] == ['call %d' % n for n in range(291, 300)]
    # A node may log anything: a long line is cut, and says so.
    assert shown['lines'][-1]['text'] == 'x' * (chase.MAX_LINE_TEXT - 1) + '…'


def test_without_a_watch_the_frame_says_no_calls(sim):
    frame = chase.chase_frame('bot::cam', 1.0, sim.sense(sim.robots()[0].sensors[0]), [])
    header, _ = split(frame)
    assert header['calls'] is None
    assert json.loads(json.dumps(header))['commands'] == []
