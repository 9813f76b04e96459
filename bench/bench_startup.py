"""Start-up: `roslaunch my_robot world.launch gui:=false` to the first camera image.

    python bench/bench_startup.py [--runs 7] [--command "roslaunch my_robot world.launch gui:=false"]
                                  [--checkouts DIR [DIR ...]]

The command runs as a student types it, with no master up, so roslaunch
starts roscore itself (on a free port of its own: ROS_MASTER_URI, not an
argument, so the command stays verbatim). This process is the listener; it is
started and warm before the clock starts, and it needs no master to exist:

- it polls the master's XML-RPC API every few milliseconds until it answers,
  then polls its system state, noting when each node, parameter and service
  of the launch appears;
- as soon as a publisher of /camera/rgb/image_raw is registered, it asks
  that publisher for the topic and reads the first message straight off the
  TCPROS socket (no rospy node of its own, whose start-up would be counted).

The figure is the wall time from Popen to the first message's last byte.
A real subscriber (a rospy node registered before the camera's publisher)
is told of the publisher by the master at the same moment this one sees it
by polling. The breakdown prints when each milestone was reached, median
and min over the runs, and the lines roslaunch and its nodes printed, with
their time, for the slowest step. Warm: one run is made first and not
counted (page cache, numba's cache). With --checkouts, the runs alternate
between the checkouts, each in the environment its env.sh makes from a
clean shell, so that a comparison sees the same load. Figures only.
"""
import argparse
import os
import shlex
import signal
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
import xmlrpc.client

TOPIC = '/camera/rgb/image_raw'
IMAGE_TYPE = 'sensor_msgs/Image'
POLL_S = 0.005
TIMEOUT_S = 60.0

# (label, test on the master's state) in the order a start-up reaches them.
MILESTONES = [
    ('master answers', lambda s: True),
    ('/rosout up', lambda s: '/rosout' in s.nodes),
    ('robot_description set', lambda s: s.has_description),
    ('flatsim registered', lambda s: '/flatsim' in s.nodes),
    ('robot_state_publisher registered', lambda s: '/robot_state_publisher' in s.nodes),
    ('urdf_spawner registered', lambda s: '/urdf_spawner' in s.nodes or s.spawner_gone),
    ('spawn service up', lambda s: '/gazebo/spawn_urdf_model' in s.services),
    ('camera publisher registered', lambda s: bool(s.camera_publishers)),
]


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


class MasterState:
    """What one getSystemState (and a getParam) said."""

    def __init__(self, master, seen_spawner):
        _code, _msg, (publishers, _subscribers, services) = master.getSystemState('/bench')
        self.nodes = {node for _topic, nodes in publishers + services for node in nodes}
        self.services = {service for service, _nodes in services}
        self.camera_publishers = [nodes for topic, nodes in publishers if topic == TOPIC]
        self.has_description = master.hasParam('/bench', '/robot_description')[2]
        # The spawner exits once the model is in: seen once, then gone, counts as registered.
        self.spawner_gone = seen_spawner and '/urdf_spawner' not in self.nodes


def read_exactly(sock, size):
    chunks = []
    while size:
        chunk = sock.recv(min(size, 1 << 20))
        if not chunk:
            raise ConnectionError('publisher closed the connection')
        chunks.append(chunk)
        size -= len(chunk)
    return b''.join(chunks)


def read_frame(sock):
    (size,) = struct.unpack('<I', read_exactly(sock, 4))
    return read_exactly(sock, size)


def first_message(master, node, md5sum):
    """Subscribe to TOPIC at node over TCPROS and return the first message's size."""
    _code, _msg, node_uri = master.lookupNode('/bench', node)
    _code, _msg, (_protocol, host, port) = xmlrpc.client.ServerProxy(node_uri).requestTopic(
        '/bench', TOPIC, [['TCPROS']])
    with socket.create_connection((host, port), timeout=TIMEOUT_S) as sock:
        fields = {'callerid': '/bench_startup', 'topic': TOPIC, 'type': IMAGE_TYPE,
                  'md5sum': md5sum, 'tcp_nodelay': '1'}
        header = b''.join(struct.pack('<I', len(item)) + item
                          for item in ('%s=%s' % pair for pair in fields.items())
                          for item in [item.encode()])
        sock.sendall(struct.pack('<I', len(header)) + header)
        reply = read_frame(sock)
        if b'error=' in reply:
            raise RuntimeError('publisher refused the subscription: %r' % reply)
        return len(read_frame(sock))


class OutputClock(threading.Thread):
    """Reads the launch's output, noting each line's wall time since start."""

    def __init__(self, stream, start):
        super().__init__(daemon=True)
        self.stream, self.start_time, self.lines = stream, start, []

    def run(self):
        for raw in self.stream:
            self.lines.append((time.monotonic() - self.start_time,
                               raw.decode(errors='replace').rstrip()))


def checkout_environment(checkout):
    """The environment `source CHECKOUT/env.sh` makes, from a clean login-like shell."""
    clean = {'HOME': os.environ.get('HOME', '/root'), 'USER': os.environ.get('USER', ''),
             'PATH': '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin',
             'LANG': os.environ.get('LANG', 'C.UTF-8')}
    dump = subprocess.run(['bash', '-c', 'source "$0/env.sh" >/dev/null 2>&1 && env -0', checkout],
                          env=clean, capture_output=True, check=True).stdout
    return dict(item.split('=', 1) for item in dump.decode().split('\0') if '=' in item)


def one_run(command, md5sum, log_dir, base_env):
    port = free_port()
    uri = 'http://localhost:%d' % port
    env = dict(base_env, ROS_MASTER_URI=uri, ROS_LOG_DIR=log_dir)
    if not env.get('ROS_IP'):
        env['ROS_HOSTNAME'] = 'localhost'
    master = xmlrpc.client.ServerProxy(uri)
    reached = {}
    start = time.monotonic()
    try:
        proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                start_new_session=True)
    except OSError as error:
        raise RuntimeError('cannot run %s: %s' % (command[0], error)) from None
    output = OutputClock(proc.stdout, start)
    output.start()
    try:
        seen_spawner = False
        while len(reached) < len(MILESTONES):
            if proc.poll() is not None or time.monotonic() - start > TIMEOUT_S:
                output.join(timeout=5)
                what = ('ended with status %d' % proc.returncode if proc.poll() is not None
                        else 'published no camera image within %.0f s' % TIMEOUT_S)
                raise RuntimeError('%s %s; its last lines:\n%s' % (
                    ' '.join(command), what, '\n'.join(line for _t, line in output.lines[-30:])))
            try:
                state = MasterState(master, seen_spawner)
            except (ConnectionError, OSError, xmlrpc.client.Fault):
                time.sleep(POLL_S)
                continue
            seen_spawner = seen_spawner or '/urdf_spawner' in state.nodes
            now = time.monotonic() - start
            for label, test in MILESTONES:
                if label not in reached and test(state):
                    reached[label] = now
            if state.camera_publishers:
                for label, _test in MILESTONES:
                    reached.setdefault(label, now)
                break
            time.sleep(POLL_S)
        size = first_message(master, state.camera_publishers[0][0], md5sum)
        reached['first image'] = time.monotonic() - start
        return reached, size, output.lines
    finally:
        try:
            os.killpg(proc.pid, signal.SIGINT)
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        except ProcessLookupError:
            pass
        output.join(timeout=5)


def run_all(command, setups, runs):
    """{setup name: [milestones of each counted run]}, and the last run's output lines."""
    from sensor_msgs.msg import Image
    results = {name: [] for name, _env in setups}
    with tempfile.TemporaryDirectory(prefix='bench_startup_') as log_dir:
        for _name, env in setups:
            one_run(command, Image._md5sum, log_dir, env)   # warm-up, not counted
        for index in range(runs):
            # Alternate the order, so that neither always runs right after the other.
            for name, env in (setups if index % 2 == 0 else setups[::-1]):
                reached, size, lines = one_run(command, Image._md5sum, log_dir, env)
                results[name].append(reached)
                print('run %d, %s: first image after %.3f s (%d bytes), load %.2f'
                      % (index + 1, name, reached['first image'], size, os.getloadavg()[0]))
    return results, lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--runs', type=int, default=7, help='counted runs (default 7)')
    parser.add_argument('--command', default='roslaunch my_robot world.launch gui:=false',
                        help='the command, as typed')
    parser.add_argument('--checkouts', nargs='+', metavar='DIR',
                        help='alternate runs between these checkouts of the project (each '
                             'built by its setup.sh); default: this shell\'s environment')
    parser.add_argument('--show-output', action='store_true',
                        help='print the last run\'s output lines with their times')
    args = parser.parse_args()
    if args.runs < 1:
        parser.error('--runs must be at least 1')
    command = shlex.split(args.command)
    if args.checkouts:
        missing = [d for d in args.checkouts if not os.path.isfile(os.path.join(d, 'env.sh'))]
        if missing:
            parser.error('no env.sh in %s' % ', '.join(missing))
        setups = [(os.path.abspath(d), checkout_environment(d)) for d in args.checkouts]
    else:
        setups = [('this shell', dict(os.environ))]
    print('command: %s' % args.command)
    print('load before: %.2f %.2f %.2f' % os.getloadavg())
    try:
        results, lines = run_all(command, setups, args.runs)
    except RuntimeError as error:
        print('bench_startup: %s' % error, file=sys.stderr)
        return 1
    labels = [label for label, _test in MILESTONES] + ['first image']
    for name, _env in setups:
        print('\n%s\nmilestone (s since Popen)             median    min    max' % name)
        for label in labels:
            values = [reached[label] for reached in results[name]]
            print('  %-34s %6.3f %6.3f %6.3f' % (label, statistics.median(values), min(values),
                                                max(values)))
    print('\nload after: %.2f %.2f %.2f' % os.getloadavg())
    if args.show_output:
        print('\nlast run\'s output:')
        for when, line in lines:
            print('  %6.3f  %s' % (when, line[:160]))
    for name, _env in setups:
        first = [reached['first image'] for reached in results[name]]
        print('first image, %s: median %.3f s, min %.3f s over %d runs'
              % (name, statistics.median(first), min(first), len(first)))


if __name__ == '__main__':
    sys.exit(main())
