"""What a flooding submission costs the grader: the commands it keeps, its node's and its
simulator's message limits, roscore's logs copied capped, and the master's bounds on calls
and parameters."""
import os

import pytest

from session_fakes import a_session


# -- what a flooding submission costs the grader ----------------------------------------------


def test_a_flood_on_cmd_vel_costs_the_grader_bounded_memory(tmp_path, monkeypatch):
    from geometry_msgs.msg import Twist
    from chase_tools.grading import bounds
    session = a_session(tmp_path, monkeypatch)
    before = len(session.cmd)
    command = Twist()
    command.linear.x = 0.3
    flood = 3 * bounds.COMMANDS_KEPT
    for _ in range(flood):
        session.on_cmd(command)
    assert len(session.cmd) - before == flood          # every command is counted
    kept = session.cmd.since(before)
    assert len(kept) == bounds.COMMANDS_KEPT   # and only the last ones are kept
    assert kept[-1] == (1.5, 0.3, 0.0)
    assert session.cmd.dropped_since(before) == flood - bounds.COMMANDS_KEPT


def test_the_graders_node_refuses_a_message_announced_larger_than_its_limit_at_its_length():
    """rospy would buffer a message of any announced length until all of it had come."""
    import io
    import socket
    import struct
    from rospy.impl.tcpros_base import TransportTerminated
    from rospy.impl.tcpros_pubsub import TCPROSSub
    from rospy.impl.tcpros_service import TCPROSServiceClient
    from std_msgs.msg import String
    from std_srvs.srv import Trigger
    from chase_tools.grading.message_limit import MessageLimit
    asked = []

    def sender(topic, port):
        asked.append((topic, port))
        return '/hostile'
    limit = MessageLimit(limit=1024, sender=sender)
    server = socket.create_server(('127.0.0.1', 0))
    left = socket.create_connection(server.getsockname())
    right, _peer = server.accept()
    server.close()
    port = right.getsockname()[1]
    try:
        within = io.BytesIO()
        String('hello').serialize(within)
        framed = io.BytesIO()
        framed.write(struct.pack('<I', len(within.getvalue())) + within.getvalue())
        taken = []
        TCPROSSub('/chatter', String).read_messages(framed, taken, left)
        assert [msg.data for msg in taken] == ['hello']
        announced = io.BytesIO()
        announced.write(struct.pack('<I', 1500000000) + b'x' * 100)
        with pytest.raises(TransportTerminated):
            TCPROSSub('/chatter', String).read_messages(announced, [], left)
        # A service's answer: an ok byte, then the length.
        answer = io.BytesIO()
        answer.write(b'\x01' + struct.pack('<I', 2000000) + b'x' * 100)
        with pytest.raises(TransportTerminated):
            TCPROSServiceClient('/serve', Trigger).read_messages(answer, [], left)
    finally:
        left.close()
        right.close()
    said = limit.notes()
    assert asked == [('/chatter', port), ('/serve', port)]
    assert len(said) == 2
    assert said[0].startswith('the grader refused a message of 1.4 GiB on /chatter from /hostile '
                              '(127.0.0.1:%d) (1 time), larger than the 1 KiB it takes' % port)
    assert said[1].startswith('the grader refused a message of 1.9 MiB on /serve from /hostile')
    limit.allow_frames(2560, 1440)
    assert limit.limit == 2560 * 1440 * 4 + (64 << 10)
    limit.allow_frames(320, 240)           # the course's camera: the floor for any message
    assert limit.limit == 8 << 20


def test_the_graders_simulator_takes_no_message_larger_than_the_graders_node_and_says_what_it_refused(
        tmp_path):
    """The simulator runs under message_limit's guard: its refusals go to its record, and the
    grader's notes name them, with the sending node found from the port."""
    import subprocess
    import sys
    record = tmp_path / 'refused.json'
    program = tmp_path / 'program.py'
    program.write_text(
        'import io, struct, sys\n'
        'from rospy.impl.tcpros_base import TransportTerminated\n'
        'from rospy.impl.tcpros_pubsub import TCPROSSub\n'
        'from geometry_msgs.msg import Twist\n'
        'class Peer:\n'
        '    def getpeername(self):\n'
        '        return ("127.0.0.1", 40404)\n'
        'bomb = io.BytesIO()\n'
        'bomb.write(struct.pack("<I", 1500000000) + bytes(64))\n'
        'try:\n'
        '    TCPROSSub("/cmd_vel", Twist).read_messages(bomb, [], Peer())\n'
        'except TransportTerminated:\n'
        '    print("REFUSED", sys.argv[1:])\n')
    done = subprocess.run([sys.executable, '-m', 'chase_tools.grading.message_limit', str(record),
                           str(program), '__name:=flatsim'], stdout=subprocess.PIPE, text=True,
                          timeout=60, check=True)
    assert done.stdout == "REFUSED ['__name:=flatsim']\n"
    from chase_tools.grading.message_limit import simulator_notes
    said = simulator_notes(record.read_text(), lambda topic, port: '/hostile' if port == 40404 else None)
    assert said == ["the grader's simulator refused a message of 1.4 GiB on /cmd_vel from /hostile "
                    "(127.0.0.1:40404) (1 time), larger than the 8 MiB it takes: the connection was "
                    "closed before it was read"]
    assert simulator_notes('{"limit": 1', None) == [
        "the grader's simulator kept a record of refused messages that could not be read"]


def test_roscores_logs_are_copied_capped_without_following_a_link_or_opening_a_fifo(tmp_path):
    from chase_tools.grading.core import Core
    box = Core(str(tmp_path / 'core'), 64 << 10, switch_user=False)
    try:
        run = os.path.join(box.log_dir, 'run_id')
        os.makedirs(run)
        with open(os.path.join(run, 'rosout.log'), 'wb') as stream:
            stream.write(b'r' * (1 << 20))
        with open(os.path.join(run, 'master.log'), 'w') as stream:
            stream.write('small\n')
        secret = tmp_path / 'secret'
        secret.write_text('not roscore\'s\n')
        os.symlink(str(secret), os.path.join(run, 'linked.log'))
        os.mkfifo(os.path.join(run, 'fifo.log'))
        out = tmp_path / 'report'
        cut = box.copy_logs(str(out))
        assert sorted(os.listdir(out / 'run_id')) == ['master.log', 'rosout.log']
        assert (out / 'run_id' / 'master.log').read_text() == 'small\n'
        assert os.path.getsize(out / 'run_id' / 'rosout.log') < (64 << 10) + 200
        assert [(name, cap.total) for name, cap in cut] == [('run_id/rosout.log', 1 << 20)]
        with open(box.logging) as stream:
            assert "args=(os.environ['ROS_LOG_FILENAME'], 'a', 32768, 1)" in stream.read()
    finally:
        box.end()


def test_the_master_refuses_calls_and_parameters_past_its_bounds_and_says_so(tmp_path):
    """The session's master under master_limit: a call past the request limit is refused before
    it is read (HTTP 413), a parameter that would take what the master holds past its limit is
    refused with the API's error code, a deleted one frees its room, and each refusal is in
    the record the report reads."""
    import socket
    import xmlrpc.client
    from rosmaster.master import Master
    from chase_tools.grading.master_limit import MasterLimit, master_notes
    record = tmp_path / 'refused.json'
    uninstall = MasterLimit(record=str(record), request_limit=1 << 20, parameters_limit=3 << 20).install()
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        port = probe.getsockname()[1]
    master = Master(port)
    master.start()
    try:
        api = xmlrpc.client.ServerProxy('http://127.0.0.1:%d/' % port)
        value = 'v' * (700 << 10)
        for index in range(4):
            assert api.setParam('/test', '/big_%d' % index, value)[0] == 1
        code, text, _ = api.setParam('/test', '/big_4', value)
        assert code == -1 and text.startswith('parameter /big_4 refused: the parameters would hold '
                                              'more than 3145728 bytes'), text
        # Setting a parameter again replaces it: no more room taken.
        assert api.setParam('/test', '/big_0', value)[0] == 1
        assert api.deleteParam('/test', '/big_1')[0] == 1
        assert api.setParam('/test', '/big_4', value)[0] == 1
        with pytest.raises(xmlrpc.client.ProtocolError) as refused:
            api.setParam('/test', '/huge', 'h' * (2 << 20))
        assert refused.value.errcode == 413
        assert api.getParam('/test', '/big_4')[2] == value
    finally:
        master.stop()
        uninstall()
    said = master_notes(record.read_text())
    assert said == [
        'the ROS master refused %s from 127.0.0.1 (the last: %s bytes): it takes no call '
        'larger than 1 MiB' % (said[0].split(' from ')[0].split('refused ')[1],
                               said[0].split('the last: ')[1].split()[0]),
        'the ROS master refused 1 parameter from /test (the last: /big_4, %d bytes): it holds at most '
        '3 MiB of parameters' % len(xmlrpc.client.dumps((value,), allow_none=True))]
    assert int(said[0].split('the last: ')[1].split()[0]) > 2 << 20
