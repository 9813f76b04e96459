"""Where the studio's address goes: the token to the private address file only, never to
the log that reaches /rosout (which every node on the ROS graph may read)."""
import types

import pytest

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


def test_the_listen_address_is_an_ip_address_or_a_clear_error():
    assert address.listen_address(' 0.0.0.0 ') == '0.0.0.0'
    assert address.listen_address('::1') == '::1'
    for wrong in ('lab-server', '', '10.0.0', 0, None):
        with pytest.raises(ValueError, match='~studio_listen must be an IP address of this machine'):
            address.listen_address(wrong)
    assert address.is_loopback('127.0.0.1') and not address.is_loopback('0.0.0.0')


def test_gazebo_listen_takes_an_address_and_a_port_and_refuses_anything_else(capsys):
    from flatsim.nodes.gazebo import parse_args, simulator_argv
    assert parse_args('gazebo', ['--listen', '0.0.0.0:8080']).listen == ('0.0.0.0', 8080)
    assert parse_args('gazebo', ['--listen', '[::]:8080']).listen == ('::', 8080)
    assert parse_args('gazebo', ['--listen', '10.1.2.3', 'my.world']).listen == ('10.1.2.3', None)
    for wrong, says in (('lab-server:8080', '--listen must be an IP address'),
                        ('0.0.0.0:http', 'the port in --listen must be a whole number'),
                        ('0.0.0.0:70000', 'the port in --listen must be a whole number')):
        with pytest.raises(SystemExit):
            parse_args('gazebo', ['--listen', wrong])
        assert says in capsys.readouterr().err
