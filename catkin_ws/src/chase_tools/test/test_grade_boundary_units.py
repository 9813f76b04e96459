"""The grader's edges that need no grade to test: its calls to what a submission serves end by a
deadline, its reports show what a submission named as text, --timeout-run is kept and passed
on, and the sandbox's limits without a cgroup leave room for the simulator."""
import http.server
import socket
import struct
import sys
import threading
import time
import types

import pytest

from markdown_check import blocks, first_table, headings, outside_fences

# A guard against a call that never ends: far beyond any deadline under test. The tests assert
# that the call ended with the error that names its deadline, never how long it took.
HANG_GUARD_S = 60.0
FORGED = '\n| `chase` | seeded placements are chased to the ball | PASS | forged |\n# Grade: PASS'


class Server:
    """A TCP server on loopback that answers each connection with answer(conn)."""

    def __init__(self, answer):
        self.sock = socket.socket()
        self.sock.bind(('127.0.0.1', 0))
        self.sock.listen(8)
        self.answer = answer
        self.received = []
        self.stopping = False
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    @property
    def port(self):
        return self.sock.getsockname()[1]

    def serve(self):
        while not self.stopping:
            try:
                conn, _peer = self.sock.accept()
            except OSError:
                return
            threading.Thread(target=self.answer, args=(conn,), daemon=True).start()

    def close(self):
        self.stopping = True
        self.sock.close()


def dripping(conn):
    """A header's length, then its bytes one every 0.3 s: each read gets something."""
    for byte in b'\x00\x01\x00\x00' + b'x' * 1000:
        try:
            conn.sendall(bytes([byte]))
        except OSError:
            return
        time.sleep(0.3)


def ended(call):
    """call()'s outcome (its exception, or its value), or fail if it has not ended by the guard."""
    outcome = {}

    def run():
        try:
            outcome['value'] = call()
        except Exception as error:  # noqa: BLE001 - the outcome under test
            outcome['error'] = error
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(HANG_GUARD_S)
    assert not thread.is_alive(), 'the call had not ended after %g s' % HANG_GUARD_S
    return outcome


@pytest.fixture
def drip_server():
    server = Server(dripping)
    yield server
    server.close()


def test_a_service_that_drips_its_header_fails_the_probe_at_its_deadline(drip_server):
    from chase_tools.grading import probe
    outcome = ended(lambda: probe.service_headers('rosrpc://127.0.0.1:%d' % drip_server.port,
                                                  '/ball_chaser/command_robot', within=1.0))
    error = outcome.get('error')
    assert isinstance(error, probe.ProbeError), outcome
    assert str(error).startswith('no whole answer within 1 s while reading'), str(error)


def test_a_call_of_a_dripping_service_fails_at_its_deadline(drip_server):
    from chase_tools.grading import course_service, probe
    srv = course_service.course_drive_to_target()
    outcome = ended(lambda: probe.call_service('rosrpc://127.0.0.1:%d' % drip_server.port,
                                               '/ball_chaser/command_robot', srv,
                                               srv._request_class(0.1, 0.2), within=1.0))
    assert isinstance(outcome.get('error'), probe.ProbeError), outcome
    assert 'no whole answer within 1 s' in str(outcome['error'])


def test_a_header_larger_than_the_cap_is_refused_unread():
    from chase_tools.grading import probe

    def huge(conn):
        conn.sendall(struct.pack('<I', 1 << 30) + b'x' * 4096)
        time.sleep(5)
        conn.close()
    server = Server(huge)
    try:
        outcome = ended(lambda: probe.service_headers('rosrpc://127.0.0.1:%d' % server.port, '/s'))
    finally:
        server.close()
    assert str(outcome.get('error')) == ('its header says it is 1073741824 bytes long, more than '
                                         'the 65536 the grader reads')


def test_a_service_that_answers_as_one_is_called_and_probed():
    """The grader's own client against the wire format rospy's servers speak."""
    from rosgraph.network import decode_ros_handshake_header, encode_ros_handshake_header
    from chase_tools.grading import course_service, probe
    srv = course_service.course_drive_to_target()
    asked = []

    def serve(conn):
        with conn:
            data = b''
            while len(data) < 4 or len(data) < 4 + struct.unpack('<I', data[:4])[0]:
                data += conn.recv(4096)
            asked.append(decode_ros_handshake_header(data))
            conn.sendall(encode_ros_handshake_header({'md5sum': srv._md5sum, 'type': srv._type,
                                                      'callerid': '/drive_bot'}))
            if asked[-1].get('probe') == '1':
                return
            request = b''
            while len(request) < 20:
                request += conn.recv(4096)
            linear, angular = struct.unpack('<dd', request[4:20])
            import io
            body = io.BytesIO()
            srv._response_class('got %.2f %.2f' % (linear, angular)).serialize(body)
            conn.sendall(struct.pack('<BI', 1, body.tell()) + body.getvalue())
    server = Server(serve)
    try:
        uri = 'rosrpc://127.0.0.1:%d' % server.port
        headers = probe.service_headers(uri, '/ball_chaser/command_robot')
        answer = probe.call_service(uri, '/ball_chaser/command_robot', srv,
                                    srv._request_class(0.25, -0.35), within=5.0)
    finally:
        server.close()
    assert headers['md5sum'] == srv._md5sum and headers['type'] == srv._type
    assert answer.msg_feedback == 'got 0.25 -0.35'
    assert asked[0]['probe'] == '1' and asked[1]['md5sum'] == srv._md5sum


def test_a_node_whose_xmlrpc_answer_drips_fails_at_its_deadline():
    from chase_tools.grading import probe

    class Dripping(http.server.BaseHTTPRequestHandler):
        def do_POST(self):
            self.send_response(200)
            self.send_header('Content-Type', 'text/xml')
            self.end_headers()
            try:
                for char in '<?xml version="1.0"?><methodResponse>' * 100:
                    self.wfile.write(char.encode())
                    self.wfile.flush()
                    time.sleep(0.3)
            except OSError:
                return              # the grader hung up at its deadline

        def log_message(self, *args):
            pass
    server = http.server.ThreadingHTTPServer(('127.0.0.1', 0), Dripping)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        proxy = probe.node_proxy('http://127.0.0.1:%d/' % server.server_address[1], within=1.0)
        outcome = ended(lambda: proxy.getPid('/grade_probe'))
    finally:
        server.shutdown()
    assert isinstance(outcome.get('error'), socket.timeout), outcome


def test_a_node_whose_answer_is_long_is_read_as_a_node_answers():
    """A node's XML-RPC server compresses an answer longer than 1400 bytes when the caller takes
    gzip: the grader does not ask for it (what is small on the wire may be large once read)."""
    from xmlrpc.server import SimpleXMLRPCServer
    from chase_tools.grading import probe
    server = SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False)
    connections = [[index, '/process_image', 'o', 'TCPROS', '/camera/rgb/image_raw', True]
                   for index in range(100)]
    server.register_function(lambda caller: [1, 'bus info', connections], 'getBusInfo')
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        answer = probe.node_proxy('http://127.0.0.1:%d/' % server.server_address[1]).getBusInfo('/g')
    finally:
        server.shutdown()
    assert answer == [1, 'bus info', connections]


def test_a_camera_connection_to_a_node_stopped_before_it_started_again_does_not_count():
    """The simulator keeps its connection to a stopped process_image until a frame fails on it,
    and the world is paused while the grader starts the launch afresh: only a connection that
    was not there before the stop says the new node is connected."""
    from xmlrpc.server import SimpleXMLRPCServer
    from chase_tools import chase_graph
    server = SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False)
    simulator_uri = 'http://127.0.0.1:%d/' % server.server_address[1]
    connections = [[3, '/process_image', 'o', 'TCPROS', '/camera/rgb/image_raw', True, ''],
                   [4, 'http://127.0.0.1:1/', 'i', 'TCPROS', '/cmd_vel', True, '']]
    server.register_function(lambda caller: [1, 'bus info', connections], 'getBusInfo')
    threading.Thread(target=server.serve_forever, daemon=True).start()

    class Master:
        @staticmethod
        def lookupNode(name):  # noqa: N802 - the master's own method name
            return {'/flatsim': simulator_uri, '/drive_bot': 'http://127.0.0.1:1/'}[name]
    try:
        stale = {link[0] for link in chase_graph.simulator_links(Master)}
        assert stale == {3, 4}
        assert chase_graph.lockstep_ready(Master, '/camera/rgb/image_raw')
        assert not chase_graph.lockstep_ready(Master, '/camera/rgb/image_raw', stale=stale)
        connections.append([9, '/process_image', 'o', 'TCPROS', '/camera/rgb/image_raw', True, ''])
        assert chase_graph.lockstep_ready(Master, '/camera/rgb/image_raw', stale=stale)
    finally:
        server.shutdown()


def test_a_simulator_service_gone_from_the_master_is_named_as_taken():
    """A node that took a service of the simulator's name and was stopped (to start afresh,
    say) takes the registration with it: the simulator never gives one up while it runs."""
    import threading as threads
    from chase_tools.grading.guard import SimulatorGuard
    simulator_uri = 'http://127.0.0.1:1/'

    class Master:
        caller_id = '/grade_probe'
        services = [['/gazebo/set_model_state', ['/flatsim']], ['/gazebo/get_model_state', ['/flatsim']]]

        def getSystemState(self):  # noqa: N802 - the master's own method name
            return [], [], self.services

        def lookupService(self, service):  # noqa: N802 - the master's own method name
            return 'rosrpc://127.0.0.1:2'

    guard = SimulatorGuard.__new__(SimulatorGuard)
    guard.master, guard.lock, guard.claims, guard.seen = Master(), threads.Lock(), [], []
    guard.refused, guard.redirected = {}, {}
    guard.uri, guard.pinned = simulator_uri, True
    guard.lookup = lambda: simulator_uri
    guard.services = guard.served_as_simulator()
    assert set(guard.services) == {'/gazebo/set_model_state', '/gazebo/get_model_state'}
    assert guard.tampering() == []
    Master.services = [['/gazebo/get_model_state', ['/flatsim']]]
    assert guard.tampering() == ['/gazebo/set_model_state is no longer registered at the master: a node that '
                                 'took it from the simulator ended and took the registration with it']
    # The simulator gone as well: its services went with it, which says nothing of the rest.
    guard.lookup = lambda: None
    assert not any('no longer registered' in line for line in guard.tampering())


def forged_grade():
    from chase_tools.grading import rubric
    grade = rubric.Grade('/submissions/alice' + FORGED, seed=0)
    for name in rubric.ITEM_NAMES:
        grade.set(name, name != 'chase', 'evidence of %s' % name)
    # A node's name at the master, in an item's evidence; log lines with fences in its excerpt.
    grade.set('process_image_calls', False, '/process_image%s\n```\n subscribes to the camera' % FORGED,
              ['  logs/ball_chaser_launch.log:3: [ERROR] ```' + FORGED,
               '```', '````' + FORGED])
    grade.notes.append('links left out of the grader\'s copy: my_robot/x%s -> /etc' % FORGED)
    grade.notes.append('a file name with a carriage return\r# Grade: PASS\u2028# Grade: PASS')
    grade.folder = 'Project' + FORGED
    grade.ignored = ['old`s' + FORGED]
    grade.advisories.append('robot stability: ' + FORGED)
    grade.trials.append(rubric.Trial(0, [0.0, 0.0, 0.0], [1.0, 0.0], error='x' + FORGED))
    return grade


def test_names_and_log_lines_that_hold_markdown_show_as_text_in_the_report():
    from chase_tools.grading import rubric
    text = rubric.markdown(forged_grade())
    assert headings(text, 1) == [r'# Go Chase It: alice\\n\| \`chase\` \| seeded placements are '
                                 r'chased to the ball \| PASS \| forged \|\\n# Grade: PASS']
    assert [line for kind, line in blocks(text)
            if kind.startswith('heading') and line.lstrip('# ').startswith('Grade')] == []
    table = first_table(text)
    assert len(table) == 2 + len(rubric.ITEM_NAMES), table
    assert [row.split('|')[1].strip() for row in table[2:]] == ['`%s`' % name for name in rubric.ITEM_NAMES]
    # Outside a fence, a forged row shows only escaped: a cell of its own line, never a row.
    for _kind, line in outside_fences(text, 'forged'):
        assert '| `chase`' not in line, line
    # The item's excerpt is there, whole, inside one fence longer than any it holds.
    fenced = [line for kind, line in blocks(text) if kind == 'fenced']
    assert fenced[0] == fenced[-1] == '`````'
    assert '  logs/ball_chaser_launch.log:3: [ERROR] ```\\n| `chase` | seeded placements are ' \
           'chased to the ball | PASS | forged |\\n# Grade: PASS' in fenced


def test_a_class_summary_shows_a_submissions_name_and_notes_as_text():
    from chase_tools.grading import gather
    rows = [gather.Row('bob' + FORGED, None, 'not graded: ' + FORGED, True),
            gather.Row('alice', forged_grade(), '', True)]
    text = gather.summary_markdown(rows, 'Graded 1 at a time.')
    assert headings(text, 1) == ['# Go Chase It: 2 submissions']
    table = first_table(text)
    assert len(table) == 4, table
    assert table[2].startswith(r'| [bob\\n\| \`chase\` \|') and 'bob%0A%7C' in table[2]
    assert [line for kind, line in outside_fences(text, 'forged') if kind != 'row'] == []


def test_timeout_run_is_parsed_and_passed_on_to_each_submissions_grade(tmp_path, capsys):
    from chase_tools.grading import cli, options, submission_grade
    args = cli.parse_args([str(tmp_path), '--timeout-run', '90', '--trials', '2'])
    assert args.timeout_run == 90.0 and submission_grade.run_time_limit(args) == 90.0
    forwarded = options.submission_args(args, cores=2)
    assert forwarded[forwarded.index('--timeout-run') + 1] == '90.0'
    assert cli.parse_args([str(tmp_path)] + forwarded).timeout_run == 90.0
    with pytest.raises(SystemExit):
        cli.parse_args([str(tmp_path), '--timeout-run', '0'])
    assert '0 must be more than 0' in capsys.readouterr().err


def test_the_run_is_bounded_by_default_by_what_its_steps_may_take(tmp_path):
    from chase_tools.grading import bounds, cli, options, submission_grade
    args = cli.parse_args([str(tmp_path), '--trials', '3', '--timeout', '60'])
    bound = submission_grade.run_time_limit(args)
    assert bound == bounds.run_wall_bound(3, 60.0)
    # Each trial may take its own wall bound, and that of starting ball_chaser.launch afresh,
    # and a fourth adds one more of each.
    assert bounds.run_wall_bound(4, 60.0) - bound == bounds.sim_wall_s(60.0) + bounds.fresh_start_wall_s()
    assert bound > 3 * bounds.sim_wall_s(60.0)
    assert '--timeout-run' not in options.submission_args(args)


def test_without_a_cgroup_the_address_space_leaves_room_for_what_processes_reserve():
    from chase_tools.grading import limits
    wanted = limits.Limits(memory=1 << 30)
    args = limits.rlimit_command(wanted, cgroups_active=False, per_uid=True)
    assert '--as=%d' % (wanted.memory + limits.AS_RESERVE) in args
    assert not any(arg.startswith('--as=') for arg in limits.rlimit_command(wanted, True, True))
    said = limits.describe(wanted, limits.Cgroups(why='no cgroup v1 memory hierarchy here'), True)
    assert '3 GiB of address space per process (the memory limit of 1 GiB and 2 GiB' in said


def test_each_sandbox_has_a_dev_shm_of_a_bounded_size(tmp_path):
    from chase_tools.grading import limits, sandbox
    box = sandbox.Sandbox(str(tmp_path / 'box'), confinement=sandbox.Confinement.create(
        str(tmp_path), limits.Limits(memory=768 << 20)))
    cmd = box.command(['true'])
    at = cmd.index('/dev/shm')
    if sandbox.bwrap_has('--size'):
        assert cmd[at - 3:at + 1] == ['--size', str(64 << 20), '--tmpfs', '/dev/shm']
    else:
        assert cmd[at - 2:at + 1] == ['--bind', box.tmp, '/dev/shm']
    assert limits.shm_size(limits.Limits(memory=256 << 20)) == 32 << 20
    assert 'a /dev/shm of 64 MiB in each sandbox' in box.confinement.describe()


if __name__ == '__main__':
    sys.exit(pytest.main([__file__, '-q']))


SLOW_TO_HEAR = '''
import os, signal, sys, time
def heard(_signum, _frame):
    time.sleep(1.5)  # a machine so busy that the handler runs late
    os.close(os.open(sys.argv[1] + '.heard', os.O_WRONLY | os.O_CREAT | os.O_EXCL))
    sys.exit(130)
signal.signal(signal.SIGINT, heard)
print('ready', flush=True)
time.sleep(60)
'''


def test_a_stopped_session_is_heard_before_the_submission_is_killed(tmp_path, monkeypatch):
    """A stop kills the submission only once the session says it heard the stop, so no item
    is judged on nodes the stop was killing, however late the session's handler runs."""
    import argparse
    import os
    import subprocess

    from chase_tools.grading import sandbox_processes, submission_grade
    result_path = str(tmp_path / 'result.json')
    proc = subprocess.Popen([sys.executable, '-c', SLOW_TO_HEAR, result_path],
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline() == 'ready\n'
    heard_when_killed = []
    monkeypatch.setattr(sandbox_processes, 'end_sandbox', lambda _confinement: heard_when_killed.append(
        os.path.exists(result_path + '.heard')))
    submission_grade.stop_running_session(proc, result_path, object(), argparse.Namespace(no_isolation=True))
    assert heard_when_killed == [True]
    assert proc.returncode == 130


def stopping_run(out_dir):
    """A world's run with what Launches needs to stop a launch, and no sandbox."""
    from chase_tools.grading.launches import Launches

    class StoppingRun(Launches):
        def log_label(self, path):
            return path[len(self.out_dir) + 1:]

    run = StoppingRun()
    run.grade = types.SimpleNamespace(notes=[])
    run.open_logs, run.asked_while_running, run.log_cuts = {}, set(), {}
    run.sandbox, run.out_dir = None, str(out_dir)
    run.chaser_log = str(out_dir / 'ball_chaser_launch.log')
    return run


# roslaunch's own words (roslaunch/pmon.py) when a node with required="true" ends; it then stops
# the launch's other nodes, which can take seconds.
REQUIRED_DIED = ('=' * 80 + 'REQUIRED process [hostile-3] has died!\nprocess has finished cleanly\n'
                 'Initiating shutdown!\n' + '=' * 80)


@pytest.mark.parametrize('said, noted', [
    (REQUIRED_DIED, 'ball_chaser.launch had ended by itself before the grader stopped it (its '
                    'required node hostile-3 had died, and roslaunch was still stopping the '
                    'rest); see ball_chaser_launch.log'),
    ('process[hostile-3]: started with pid [7]', None),
])
def test_a_launch_still_stopping_after_a_required_node_died_is_said_to_have_ended(tmp_path, said,
                                                                                    noted):
    from chase_tools.grading.logcap import CappedLog
    from chase_tools.procs import ProcessGroup
    run = stopping_run(tmp_path)
    group = ProcessGroup(env={'PATH': '/usr/bin:/bin'})
    log = CappedLog(run.chaser_log, 1 << 20)
    try:
        group.start([sys.executable, '-c', 'import sys, time; print(sys.argv[1], flush=True); '
                     'time.sleep(1)', said], log)
    finally:
        log.started()
    run.open_logs[id(group)] = [log]
    time.sleep(0.3)
    assert group.alive()
    run.stop_launch(group, 'ball_chaser.launch')
    assert [note for note in run.grade.notes if 'ended by itself' in note] == (
        [noted] if noted else [])
