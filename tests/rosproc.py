"""Run ROS 1 systems for cross-package tests: a master on its own port, roslaunch
processes against it, and the pids, services and memory of their nodes.

    with RosSystem(tmp_path) as ros:
        ros.launch('world', 'my_robot', 'world.launch', 'gui:=false')
        ros.graph.wait_for_service('/gazebo/get_model_state')
        old_pid = ros.graph.kill_node('/drive_bot')
        run_forked(check_something, ros.graph)   # rospy work, in a child process

Nothing here initialises rospy: a process can hold one rospy node only, bound
to one master, so code that needs rospy (sim time, subscriptions) runs in a
forked child through run_forked(), one per test.
"""
import concurrent.futures
import multiprocessing
import os
import signal
import socket
import subprocess
import threading
import time
import xmlrpc.client

import rosgraph

# Ports start_master tries when another process takes the one it chose.
MASTER_PORT_TRIES = 3
STARTUP_TIMEOUT_S = 60.0


def free_port():
    """A TCP port on loopback that nothing listens on right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


def wait_until(predicate, wall_timeout, interval=0.1):
    """Poll predicate until it returns something truthy (returned) or wall_timeout passes (None)."""
    deadline = time.monotonic() + wall_timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            return None
        time.sleep(interval)


def vm_rss_kib(pid):
    """Resident set size of a process in KiB, from /proc/<pid>/status."""
    with open('/proc/%d/status' % pid) as status:
        for line in status:
            if line.startswith('VmRSS:'):
                return int(line.split()[1])
    raise ValueError('process %d reports no VmRSS' % pid)


_TCP_LISTEN = '0A'


def listening_sockets(pid):
    """[(address, port)] of the TCP sockets that process pid listens on (IPv4 and IPv6).

    Reads /proc/<pid>/net/tcp{,6} (the whole network namespace) and keeps the
    sockets whose inodes are among the process's open file descriptors.
    """
    fd_dir = '/proc/%d/fd' % pid
    inodes = set()
    for fd in os.listdir(fd_dir):
        try:
            target = os.readlink(os.path.join(fd_dir, fd))
        except FileNotFoundError:
            continue
        if target.startswith('socket:['):
            inodes.add(target[len('socket:['):-1])
    found = []
    for table, family in (('tcp', socket.AF_INET), ('tcp6', socket.AF_INET6)):
        try:
            with open('/proc/%d/net/%s' % (pid, table)) as lines:
                rows = [line.split() for line in lines.readlines()[1:]]
        except FileNotFoundError:
            continue
        for row in rows:
            local, state, inode = row[1], row[3], row[9]
            if state == _TCP_LISTEN and inode in inodes:
                address, port = local.split(':')
                found.append((_proc_net_address(address, family), int(port, 16)))
    return found


def _proc_net_address(hex_address, family):
    # The kernel prints each 32-bit word of the address in host (little-endian) order.
    raw = bytes.fromhex(hex_address)
    words = b''.join(raw[i:i + 4][::-1] for i in range(0, len(raw), 4))
    return socket.inet_ntop(family, words)


def is_loopback(address):
    return address.startswith('127.') or address == '::1' or address.startswith('::ffff:127.')


def run_forked(function, *args):
    """Call function(*args) in a forked child and return its result or raise its exception.

    The child can call rospy.init_node against any master; the test process stays clean.
    """
    context = multiprocessing.get_context('fork')
    with concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=context) as pool:
        return pool.submit(function, *args).result()


class ReadAsItComes:
    """A process started in a session of its own, its stdout and stderr read as they come."""

    def __init__(self, argv, **popen_args):
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     start_new_session=True, **popen_args)
        self.lines = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.proc.stdout:
            self.lines.append(line)

    @property
    def output(self):
        return ''.join(self.lines)


class RosSystem:
    """A roscore on a port of its own and the roslaunch processes started against it.

    Every process runs in its own session so stop() can end its whole group;
    each one's output goes to <log_dir>/<name>.log. The master is started
    separately from the launches, so a launch can end and start again on it.
    """

    def __init__(self, log_dir, port=None, env=None):
        """env: the environment its processes start from (default: this process's),
        such as an overlay's Overlay.env()."""
        self.log_dir = str(log_dir)
        self.port_given = port is not None
        self.env = dict(os.environ if env is None else env, ROS_LOG_DIR=os.path.join(self.log_dir, 'ros_log'))
        if not self.env.get('ROS_IP'):
            self.env.setdefault('ROS_HOSTNAME', 'localhost')
        self.use_port(port or free_port())
        self.procs = {}
        self._logs = []

    def use_port(self, port):
        self.port = port
        self.master_uri = self.env['ROS_MASTER_URI'] = 'http://localhost:%d' % port
        self.graph = RosGraph(self.master_uri)

    def __enter__(self):
        self.start_master()
        return self

    def __exit__(self, *_exc):
        self.stop()

    # -- processes ---------------------------------------------------------
    def run(self, name, cmd):
        """Start a command (argv list) against this master; name labels its log."""
        log = open(os.path.join(self.log_dir, '%s.log' % name), 'a')
        self._logs.append(log)
        proc = subprocess.Popen(cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, start_new_session=True)
        self.procs[name] = proc
        return proc

    def start_master(self):
        """roscore on self.port; on another port when this one was chosen here and another
        process took it first (free_port only says that it was free when asked)."""
        for _attempt in range(MASTER_PORT_TRIES):
            roscore = self.run('roscore', ['roscore', '-p', str(self.port)])
            wait_until(lambda: self._master_up() or roscore.poll() is not None, STARTUP_TIMEOUT_S)
            if self._master_up():
                return
            if roscore.poll() is None or self.port_given:
                break
            self.use_port(free_port())
        raise RuntimeError('roscore on port %d did not start; see %s/roscore.log'
                           % (self.port, self.log_dir))

    def _master_up(self):
        try:
            return self.graph.node_uri('/rosout')
        except xmlrpc.client.Fault:
            return None     # another XML-RPC server holds the port: not a master

    def launch(self, name, *args):
        """Start `roslaunch <args>` on this master; name labels its log."""
        old = self.procs.get(name)
        if old is not None and old.poll() is None:
            raise RuntimeError('launch %s is still running' % name)
        return self.run(name, ['roslaunch', '-p', str(self.port), '--wait'] + list(args))

    def alive(self, name):
        return self.procs[name].poll() is None

    def wait_exit(self, name, wall_timeout=30.0):
        """True when the named process ended within wall_timeout."""
        try:
            self.procs[name].wait(timeout=wall_timeout)
        except subprocess.TimeoutExpired:
            return False
        return True

    def stop(self):
        """SIGINT every process group at once; SIGKILL what lingers after 20 s."""
        running = [proc for proc in self.procs.values() if proc.poll() is None]
        for proc in running:
            _signal_group(proc, signal.SIGINT)
        deadline = time.monotonic() + 20.0
        for proc in running:
            try:
                proc.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                _signal_group(proc, signal.SIGKILL)
                proc.wait()
        for log in self._logs:
            log.close()
        self._logs = []

    def log_tail(self, name, chars=4000):
        with open(os.path.join(self.log_dir, '%s.log' % name), errors='replace') as log:
            return log.read()[-chars:]


class RosGraph:
    """Nodes and services registered with one master, by its URI (picklable, so
    run_forked() children can take it)."""

    def __init__(self, master_uri):
        self.master_uri = master_uri

    def master(self):
        return rosgraph.Master('/rosproc', master_uri=self.master_uri)

    def service_uri(self, service):
        try:
            return self.master().lookupService(service)
        except (OSError, rosgraph.MasterError):
            return None

    def wait_for_service(self, service, wall_timeout=STARTUP_TIMEOUT_S):
        """The service's rosrpc URI once it is registered, or raise after wall_timeout."""
        uri = wait_until(lambda: self.service_uri(service), wall_timeout, interval=0.2)
        if uri is None:
            raise RuntimeError('service %s did not appear within %g s' % (service, wall_timeout))
        return uri

    def node_uri(self, node):
        try:
            return self.master().lookupNode(node)
        except (OSError, rosgraph.MasterError):
            return None

    def node_pid(self, node):
        """The pid of a registered node that answers its XML-RPC getPid, else None."""
        uri = self.node_uri(node)
        if uri is None:
            return None
        try:
            code, _msg, pid = xmlrpc.client.ServerProxy(uri).getPid('/rosproc')
        except OSError:
            return None
        return pid if code == 1 else None

    def wait_for_node(self, node, wall_timeout=STARTUP_TIMEOUT_S, not_pid=None):
        """The pid of node once it answers (and differs from not_pid), or raise."""
        def new_pid():
            pid = self.node_pid(node)
            return pid if pid != not_pid else None

        pid = wait_until(new_pid, wall_timeout, interval=0.2)
        if pid is None:
            raise RuntimeError('node %s did not answer within %g s' % (node, wall_timeout))
        return pid

    def nodes(self):
        """Names of every node the master knows as a publisher, subscriber or service provider."""
        names = set()
        for group in self.master().getSystemState():
            for _topic, providers in group:
                names.update(providers)
        return sorted(names)

    def kill_node(self, node, sig=signal.SIGKILL):
        """Send sig to the node's process and wait until it is gone; returns the old pid."""
        pid = self.wait_for_node(node, wall_timeout=10.0)
        os.kill(pid, sig)
        if not wait_until(lambda: not _running(pid), 10.0):
            raise RuntimeError('node %s (pid %d) did not die on signal %d' % (node, pid, sig))
        return pid

    def shutdown_node(self, node):
        """Ask a node to exit through its XML-RPC shutdown, as `rosnode kill` does; returns its pid."""
        pid = self.wait_for_node(node, wall_timeout=10.0)
        try:
            xmlrpc.client.ServerProxy(self.node_uri(node)).shutdown('/rosproc', 'shut down by a test')
        except OSError:
            pass  # a node may close its XML-RPC server before the reply gets out
        if not wait_until(lambda: not _running(pid), 20.0):
            raise RuntimeError('node %s (pid %d) did not shut down' % (node, pid))
        return pid


def _running(pid):
    """False for a process that is gone or a zombie awaiting its parent."""
    try:
        with open('/proc/%d/stat' % pid) as stat:
            return stat.read().rsplit(')', 1)[1].split()[0] != 'Z'
    except FileNotFoundError:
        return False


def _signal_group(proc, sig):
    try:
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        pass


class Probe:
    """The test's own rospy node, for use inside run_forked() only.

    It follows /clock when the master's /use_sim_time is set, so start it after
    the world launch has set that parameter.
    """

    def __init__(self, master_uri, name='probe'):
        os.environ['ROS_MASTER_URI'] = master_uri
        if not os.environ.get('ROS_IP'):
            os.environ.setdefault('ROS_HOSTNAME', 'localhost')
        import rospy  # imported here so the test process itself never loads rospy's globals
        from gazebo_msgs.srv import GetModelState
        self.rospy = rospy
        rospy.init_node(name, anonymous=True, disable_signals=True)
        self._get_state = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)

    def sim_time(self):
        return self.rospy.get_time()

    def model_state(self, name):
        """The gazebo_msgs/GetModelState response for a model; raises if the model is unknown."""
        response = self._get_state(model_name=name)
        if not response.success:
            raise RuntimeError('get_model_state %s: %s' % (name, response.status_message))
        return response

    def gap(self, model_a='my_robot', model_b='white_ball'):
        """Distance in the plane between two models' origins (m)."""
        a = self.model_state(model_a).pose.position
        b = self.model_state(model_b).pose.position
        return ((a.x - b.x) ** 2 + (a.y - b.y) ** 2) ** 0.5

    def call_empty(self, service):
        from std_srvs.srv import Empty
        self.rospy.wait_for_service(service, timeout=STARTUP_TIMEOUT_S)
        self.rospy.ServiceProxy(service, Empty)()

    def wait_sim(self, predicate, sim_timeout, wall_timeout, interval=0.05):
        """Poll predicate until truthy (returned), or until sim_timeout seconds of sim time
        or wall_timeout seconds of wall time pass (None). Sim time going back restarts the count."""
        start = last = self.sim_time()
        deadline = time.monotonic() + wall_timeout
        while True:
            value = predicate()
            if value:
                return value
            now = self.sim_time()
            if now < last:
                start = now
            last = now
            if now - start > sim_timeout or time.monotonic() > deadline:
                return None
            time.sleep(interval)

    def close(self):
        self.rospy.signal_shutdown('probe done')
