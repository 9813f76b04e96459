"""prompt_init.init_node: rospy.init_node, whose wait for its own registration naps 5 ms, not 0.1 s."""
import time

import pytest
import rospy
import rospy.impl.init

from flatsim.ros import prompt_init


@pytest.fixture
def naps(monkeypatch):
    taken = []
    monkeypatch.setattr(time, 'sleep', taken.append)
    return taken


def registering_init_node(calls):
    """What rospy.init_node does while it waits: nap 0.1 s on rospy.impl.init's time."""
    def init_node(name, **kwargs):
        calls.append((name, kwargs))
        rospy.impl.init.time.sleep(0.1)
        rospy.impl.init.time.sleep(0.00001)
        assert rospy.impl.init.time.monotonic() > 0   # the rest of time is time's
    return init_node


def test_the_registration_wait_naps_briefly(monkeypatch, naps):
    calls = []
    monkeypatch.setattr(rospy, 'init_node', registering_init_node(calls))
    prompt_init.init_node('flatsim', log_level=rospy.INFO)
    assert calls == [('flatsim', {'log_level': rospy.INFO})]
    assert naps == [prompt_init.REGISTRATION_POLL_S, 0.00001]
    assert prompt_init.REGISTRATION_POLL_S <= 0.01
    assert rospy.impl.init.time is time


def test_rospy_keeps_its_own_time_after_a_failed_init(monkeypatch):
    def failing(name, **kwargs):
        raise rospy.ROSInitException('no master')
    monkeypatch.setattr(rospy, 'init_node', failing)
    with pytest.raises(rospy.ROSInitException):
        prompt_init.init_node('flatsim')
    assert rospy.impl.init.time is time


def test_another_rospy_gets_its_own_wait(monkeypatch, naps):
    """A rospy whose init module no longer naps on the time module is left alone."""
    monkeypatch.delattr(rospy.impl.init, 'time')
    calls = []
    monkeypatch.setattr(rospy, 'init_node', lambda name, **kwargs: calls.append(name))
    prompt_init.init_node('flatsim')
    assert calls == ['flatsim'] and not hasattr(rospy.impl.init, 'time')
