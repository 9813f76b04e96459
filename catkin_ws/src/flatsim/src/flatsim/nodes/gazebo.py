"""gazebo: the simulator (flatsim) with its window (the studio page), as Gazebo's command.

  gazebo [-u] [--verbose] [--listen ADDRESS[:PORT]] [WORLD]    # also rosrun gazebo_ros gazebo
  gzserver [-u] [--verbose] [--listen ADDRESS[:PORT]] [WORLD]  # the simulator alone, no window

WORLD is an SDF .world file; without one the world is empty. The world is
loaded without any robot. -u starts with physics paused. The window's File >
Save World writes over WORLD.

With a ROS master at ROS_MASTER_URI, the simulator joins it (its /gazebo
services and topics appear there, as with gazebo_ros). Without one, the
command starts roscore on that URI's port, as roslaunch does, says so, and
stops it again on exit. It refuses to start a second simulator on a master
that has one. Ctrl-C or SIGTERM stops everything it started.

--listen serves the window's page on ADDRESS (an IP address of this machine; 0.0.0.0 for every
one), on PORT if given, instead of 127.0.0.1 only: for a browser on another machine or outside a
container. It warns, and the page still needs its token.
"""
import argparse
import os
import signal
import subprocess
import sys
import time
import urllib.parse

import roslib.packages
import rosgraph

from flatsim.errors import FlatsimError
from flatsim.nodes import gzclient
from flatsim.ros import second_server
from flatsim.studio import address

MASTER_TIMEOUT = 30.0
STOP_TIMEOUT = 10.0
SIMULATOR_NODE = '/flatsim'
LOCAL_HOSTS = ('localhost', '127.0.0.1', '::1')


def parse_args(prog, argv):
    parser = argparse.ArgumentParser(prog=prog, description=__doc__.split('\n')[0])
    parser.add_argument('world', nargs='?', default='', help='SDF .world file (default: an empty world)')
    parser.add_argument('-u', '--pause', action='store_true', help='start with physics paused')
    parser.add_argument('--verbose', action='store_true',
                        help='accepted: flatsim always reports what it skipped')
    parser.add_argument('-e', '--physics', default='ode',
                        help='accepted and ignored: flatsim has one physics engine')
    parser.add_argument('--listen', metavar='ADDRESS[:PORT]', type=listen_option,
                        help='serve the window\'s page on this address of the machine (0.0.0.0: '
                             'every address) instead of 127.0.0.1 only, on PORT if given; the page '
                             'still needs its token')
    return parser.parse_args(argv)


def listen_option(value):
    """(address, port or None) of --listen ADDRESS[:PORT]; [v6]:PORT for an IPv6 address."""
    text = value.strip()
    port = None
    if text.startswith('['):
        host, _, rest = text[1:].partition(']')
        if rest:
            if not rest.startswith(':'):
                raise argparse.ArgumentTypeError('%r is no ADDRESS[:PORT]' % value)
            port = rest[1:]
    elif text.count(':') == 1:
        host, port = text.split(':')
    else:
        host = text
    try:
        host = address.listen_address(host)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error).replace('~studio_listen', '--listen')) from None
    if port is not None and not (port.isdigit() and 0 < int(port) <= 65535):
        raise argparse.ArgumentTypeError('the port in --listen must be a whole number from 1 to '
                                         '65535, got %r' % port)
    return host, None if port is None else int(port)


def world_path(prog, world):
    """The world file's absolute path, after checking that it is there."""
    path = os.path.abspath(world)
    if not os.path.isfile(path):
        raise SystemExit('%s: cannot open the world file %s: no such file' % (prog, world))
    return path


def check_world(prog, world, path):
    """Load the world as flatsim will, to say clearly what is wrong with it."""
    from flatsim.loading.sdf_world import load_world  # numpy and friends: only when needed
    try:
        load_world(path)
    except FlatsimError as error:
        raise SystemExit('%s: cannot load the world %s: %s' % (prog, world, error)) from None


def master_online(master_uri):
    try:
        rosgraph.Master('/gazebo', master_uri=master_uri).getPid()
    except Exception:  # noqa: BLE001 - any failure to answer means no master
        return False
    return True


class Processes:
    """What the command started, stopped in reverse order."""

    def __init__(self):
        self.started = []

    def start(self, name, argv):
        # A session of its own: Ctrl-C reaches this command only, which stops them in order.
        proc = subprocess.Popen(argv, start_new_session=True, stdin=subprocess.DEVNULL)
        self.started.append((name, proc))
        return proc

    def stop(self, sig=signal.SIGINT, whole_group=False):
        """whole_group: sig goes to what each started too, such as the rosversion that a
        starting roscore runs, which a roscore stopped alone leaves writing to a closed pipe."""
        for _name, proc in reversed(self.started):
            if proc.poll() is None:
                try:
                    if whole_group:
                        os.killpg(proc.pid, sig)
                    else:
                        proc.send_signal(sig)
                except ProcessLookupError:
                    pass                # it ended meanwhile
                try:
                    proc.wait(STOP_TIMEOUT)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        self.started = []


def start_master(prog, master_uri, processes):
    parts = urllib.parse.urlsplit(master_uri)
    if (parts.hostname or '') not in LOCAL_HOSTS:
        raise SystemExit('%s: no ROS master answers at %s, and it is not on this machine; '
                         'start it there first' % (prog, master_uri))
    port = parts.port or address.DEFAULT_MASTER_PORT
    print('%s: no ROS master at %s: starting roscore on port %d (it stops with %s)'
          % (prog, master_uri, port, prog), flush=True)
    return processes.start('roscore', ['roscore', '-p', str(port)])


def wait_for_master(prog, master_uri, roscore):
    deadline = time.monotonic() + MASTER_TIMEOUT
    while not master_online(master_uri):
        if roscore.poll() is not None:
            raise SystemExit('%s: roscore exited with %d' % (prog, roscore.returncode))
        if time.monotonic() > deadline:
            raise SystemExit('%s: roscore did not answer within %g s' % (prog, MASTER_TIMEOUT))
        time.sleep(0.05)


def simulator_argv(world, paused, listen=None):
    found = roslib.packages.find_node('flatsim', 'simulator')
    if not found:
        raise SystemExit('flatsim\'s simulator is not built: run ./setup.sh')
    argv = [found[0], '__name:=flatsim', '_studio:=true', '_studio_first:=true',
            '_world_name:=%s' % world,
            '_studio_save_over_world:=%s' % ('true' if world else 'false')]
    if paused:
        argv.append('_paused:=true')
    if listen is not None:
        host, port = listen
        argv.append('_studio_listen:=%s' % host)
        if port is not None:
            argv.append('_studio_port:=%d' % port)
    return argv


def run(prog, gui):
    args = parse_args(prog, rosgraph.myargv(sys.argv)[1:])
    world = world_path(prog, args.world) if args.world else ''
    if args.listen is not None and not address.is_loopback(args.listen[0]):
        print('%s: warning: %s' % (prog, address.exposed_warning(*args.listen)), file=sys.stderr,
              flush=True)
    gzclient.install_stop_handlers()
    master_uri = rosgraph.get_master_uri()
    processes = Processes()
    try:
        roscore = None
        if not master_online(master_uri):
            roscore = start_master(prog, master_uri, processes)
        elif second_server.live_node(SIMULATOR_NODE, master_uri) is not None:
            raise SystemExit('%s: a simulator already runs on the master at %s (%s); open its '
                             'window with gzclient' % (prog, master_uri, SIMULATOR_NODE))
        # Started at once: it loads while roscore starts, and waits for the master itself.
        simulator = processes.start('flatsim', simulator_argv(world, args.pause, args.listen))
        if world:
            # Meanwhile: the simulator takes longer to get to the world than this takes.
            try:
                check_world(prog, args.world, world)
            except SystemExit:
                # SIGTERM: the simulator may not have set up its handlers yet, and Python
                # answers SIGINT there with a traceback. Nothing started needs a clean stop yet.
                processes.stop(signal.SIGTERM, whole_group=True)
                raise
        if gui:
            # The simulator serves its page while roscore starts: shown as soon as it answers.
            path = address.address_path(master_uri)
            url = gzclient.wait_for_studio(
                path, prog, master_uri, pid=simulator.pid,
                still_waiting=lambda: simulator.poll() is None and (roscore is None
                                                                    or roscore.poll() is None))
            if url is not None:
                gzclient.show(url, prog)
        if roscore is not None:
            wait_for_master(prog, master_uri, roscore)
        code = simulator.wait()
        if code != 0:
            raise SystemExit('%s: the simulator stopped with exit status %d (see its messages '
                             'above)' % (prog, code))
    except gzclient.Stop:
        pass
    finally:
        processes.stop()


def main():
    run('gazebo', gui=True)
