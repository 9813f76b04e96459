"""Where the studio's address goes: the token to the private address file only, never to
the log that reaches /rosout (which every node on the ROS graph may read)."""
import types

import rospy

from flatsim.ros import studio_world
from flatsim.studio import address

URL = 'http://127.0.0.1:40123/?token=s3cret-Token_value'


def test_without_token_keeps_the_host_port_and_page():
    assert address.without_token(URL) == 'http://127.0.0.1:40123/'
    assert address.without_token('http://127.0.0.1:40123?token=abc') == 'http://127.0.0.1:40123/'


def test_the_simulator_logs_its_studio_without_the_token(monkeypatch, tmp_path):
    logged = []

    def log(text, *args):
        logged.append(text % args)
    for level in ('logdebug', 'loginfo', 'logwarn', 'logerr', 'logfatal'):
        monkeypatch.setattr(rospy, level, log)
    server = types.SimpleNamespace(hub=types.SimpleNamespace(world=types.SimpleNamespace(node=None)))
    path = str(tmp_path / 'studio' / 'localhost_11311.json')
    studio = studio_world.RunningStudio(server, path, URL)
    studio.attach(node=object())
    (line,) = logged
    assert 'http://127.0.0.1:40123/' in line and path in line
    assert 's3cret' not in line and '?token=' not in line
