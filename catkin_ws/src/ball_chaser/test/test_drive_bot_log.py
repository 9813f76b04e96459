"""drive_bot logs every call it answers at DEBUG, request and answer on one line: a service call
is seen by no other node, so this line is how the studio's chase view shows the calls."""
import threading
import types

import pytest

from ball_chaser.drive_logic import CommandWatchdog, DriveLimits
from ball_chaser.nodes import drive_bot


@pytest.fixture
def node(monkeypatch):
    logged = []
    for level in ('logdebug', 'loginfo', 'logwarn', 'logerr'):
        monkeypatch.setattr(drive_bot.rospy, level,
                            lambda text, *args, level=level: logged.append((level, text % args)))
    monkeypatch.setattr(drive_bot.rospy, 'get_time', lambda: 4.0)
    published = []
    bot = drive_bot.DriveBot.__new__(drive_bot.DriveBot)
    bot.limits = DriveLimits(1.0, 2.0)
    bot.watchdog = CommandWatchdog(0.0)
    bot._lock = threading.Lock()
    bot.publisher = types.SimpleNamespace(publish=published.append)
    return types.SimpleNamespace(bot=bot, logged=logged, published=published)


def request(linear_x, angular_z):
    return types.SimpleNamespace(linear_x=linear_x, angular_z=angular_z)


def test_each_call_is_one_debug_line_with_the_request_and_the_answer(node):
    answer = node.bot.handle_command(request(0.5, -0.25))
    assert node.logged == [('logdebug', 'command_robot: linear_x=0.5 angular_z=-0.25 -> '
                                        + answer.msg_feedback)]
    node.logged.clear()
    answer = node.bot.handle_command(request(3.0, 0.0))
    # A clamped request: the warning, then the call as asked and as answered.
    assert node.logged == [('logwarn', answer.msg_feedback),
                           ('logdebug', 'command_robot: linear_x=3 angular_z=0 -> ' + answer.msg_feedback)]
    assert 'linear_x=1 m/s' in answer.msg_feedback


def test_a_refused_call_is_logged_with_its_request_too(node):
    with pytest.raises(drive_bot.rospy.ServiceException):
        node.bot.handle_command(request(float('nan'), 0.0))
    assert node.published == []
    level, text = node.logged[-1]
    assert level == 'logdebug'
    assert text.startswith('command_robot: linear_x=nan angular_z=0 -> refused drive request: linear_x')
    with pytest.raises(drive_bot.rospy.ServiceException):
        node.bot.handle_command(request(10 ** 400, 0.0))
    assert node.logged[-1][1].startswith('command_robot: linear_x=an integer too large for a float')
