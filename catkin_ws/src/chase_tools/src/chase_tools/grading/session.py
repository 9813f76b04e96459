"""The rubric run of one built submission, headless, in a network namespace of its own.

grade.py starts this module in a fresh process inside a network namespace that
holds only loopback (sandbox.network_namespace_command), while the build runs.
Here it starts a ROS master (trusted), waits for the built workspace (SessionSpec.
await_build), launches the submission's world.launch and ball_chaser.launch
inside the sandbox, then checks, in order:

  world_launches      the simulator comes up, the robot is spawned, the world has a white ball;
  sensors             a camera image on /camera/rgb/image_raw and a scan on /scan;
  drive_bot_service   with sim time running: /ball_chaser/command_robot has the course's
                      DriveToTarget type, and a request comes out on /cmd_vel as asked;
  chase               N seeded placements (whole ball in the robot's camera view), each
                      chased until the robot's outline comes within the reach of the
                      ball's surface or the time runs out; each failed trial says why
                      (grading/trials.py), and a PNG of each; extra worlds take a
                      share of the trials (TrialWorld, grading/worlds.py);
  process_image_calls the node subscribed to the camera called the service during the chase;
  stops_without_ball  the robot drives toward the ball, the ball is taken away, and the
                      robot's command and motion must come to zero.

process_image's calls are counted without touching its code: its launch file
(in the grader's copy) remaps the absolute name /ball_chaser/command_robot to
/grader/command_robot, where this process serves a stand-in that records each
request and forwards it to drive_bot. roscpp and rospy both apply remappings
to absolute names. The stand-in serves the course's DriveToTarget only: a
drive_bot that serves another type gets its calls straight from process_image,
uncounted, so that the chase is judged on the submission's own wiring.

A ball_chaser.launch that includes world.launch is the one launch, as its
README would run it: a second world.launch would be a second simulator.

What the grader asks of the submission's nodes (the probe of drive_bot's
header, its calls, a node's XML-RPC interface) ends by a deadline for the
whole exchange and reads a bounded answer (grading/probe.py): a node that
answers one byte at a time holds nothing. The run as a whole is bounded by
the grader (--timeout-run), whose SIGINT stops it like any stop; the notes
then say which step was under way (note_unfinished).

  python -m chase_tools.grading.session SPEC.json RESULT.json
  python -m chase_tools.grading.session --world SPEC.json      # an extra world
"""
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import xmlrpc.client
from dataclasses import asdict, dataclass

import numpy as np
import rosgraph
import rospy
from geometry_msgs.msg import Point, Twist
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Image, LaserScan
from std_msgs.msg import String

from chase_tools import chase_graph, placement
from chase_tools.chase_graph import CAMERA_TOPIC, NEW_RUN_STAMP_S
from chase_tools.grading import (course_service, evidence, launchread, probe, rubric, simulator,
                                  submission, trials, worldcopy)
from chase_tools.grading.core import Core, logging_config
from chase_tools.grading.limits import Limits, size_text
from chase_tools.grading.logcap import CappedLog, run_captured
from chase_tools.grading.message_limit import RECORD_LIMIT, MessageLimit, simulator_notes
from chase_tools.grading.sandbox import (Confinement, Sandbox, allowed_environment, cache_stand_ins,
                                         end_sandbox, environment_paths, process_name,
                                         sandbox_children)
from chase_tools.grading.scratch import hand_over, read_beneath, write_new
from chase_tools.grading.worlds import free_port
from chase_tools.procs import ProcessGroup, wait_until
from flatsim.errors import FlatsimError
from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg

SCAN_TOPIC = '/scan'
DRIVE_PROBE = (0.25, -0.35)    # a request no controller sends by chance
FLOAT_TOLERANCE = 1e-4         # C++ nodes often pass the request through float
ANSWER_NOTED_S = 0.05          # an answer that took this much sim time or more says so
COMMAND_WAIT_S = 2.0           # wall seconds after the answer for the asked command to show
STILL_SPEED = 0.01             # m/s and rad/s: a command this small counts as stopped
STILL_DISTANCE_M = 0.05
STILL_TURN_RAD = 0.05
REACT_S = 1.0                  # sim time the node gets to react to the ball's going
WATCH_S = 2.0                  # sim time the robot must then stay still
STOP_GRACE_S = 3.0
# Why the items not yet run failed when the session was stopped; the grader says by what.
STOPPED = 'the grade was stopped'
# How a trial or an item judged on a simulator that another node impersonated begins its error.
TAMPERED = 'not judged: the simulator was impersonated'
TAMPERING_SHOWN = 3             # of what the guard found, what a verdict quotes
# How a trial or an item begins its error when a model moved in a way no chase moves it: through
# the simulator's API by another node than the grader (flatsim's ~model_moves), or the robot
# faster than it could drive (trials.first_jump).
MOVED = 'not judged: the models were moved during the trial'
MOVES_SHOWN = 3
MOVES_KEPT = 100                # of the moves of one trial, what the grader keeps
# Wall seconds the grader waits for flatsim to say it made the grader's own placements.
MOVES_SEEN_S = 2.0
# Wall seconds between looks at something the run waits for (the master, the world, a service).
POLL_S = 0.05
# flatsim's ~model_states_rate when the launch does not set it (Hz of sim time).
DEFAULT_STATES_RATE = 50.0
# Wall seconds an extra world's chaser has to answer for the first time (TrialWorld.warm_up).
WARM_UP_S = 10.0
# Sim seconds a state's counted time may differ from the grader's /clock when it came.
STATES_CLOCK_TOLERANCE_S = 1.0
# Sim seconds at the start of a trial during which the camera's frames are checked for the ball.
FRAME_WATCH_S = 2.0
WORLD_COPY_S = 60.0            # wall seconds for the sandbox to copy the world (worldcopy.py)
LAUNCH_READ_S = 60.0           # wall seconds for the sandbox to read the world's launch (launchread.py)
WORLD_COPY_LOG = 64 << 10
# What the grader keeps of what a submission can send as fast as it likes (trials.RollingLog):
# commands on /cmd_vel, process_image's calls, and the model states of a trial (50 Hz of sim
# time by default, 3000 in a 60 s trial). Memory stays bounded however much comes.
COMMANDS_KEPT = 20000
CALLS_KEPT = 20000
STATES_KEPT = 30000
# Model states waiting for the grader's callback. rospy deserializes what one read of the socket
# holds (64 KiB) into that queue, dropping the oldest beyond it, then calls back for each on the
# connection's own thread: a flatsim state of a few models takes some 500 bytes, so no state of
# the simulator's is dropped (the trials count them, trials.state_times), and a flood of small
# messages on another connection is bounded all the same.
STATES_QUEUE = 256
# Wall seconds between the guard's looks for the simulator at the master, while none is known.
LOOKUP_EVERY_S = 0.5
# Wall seconds the guard waits for a node to say where it takes connections.
NODE_ANSWER_S = 2.0
# Wall seconds drive_bot has to answer a call of the grader's, or one it forwards.
DRIVE_CALL_S = 10.0
FORWARD_S = 10.0
# setuptools' stand-in for distutils, which the venv puts first, costs every roslaunch and
# xacro about 0.2 s of imports (rosclean asks for distutils); the standard library's does
# the same job for them.
QUICK_START = {'SETUPTOOLS_USE_DISTUTILS': 'stdlib'}
# The grader's simulator's record of the messages it refused, in its own folder.
SIMULATOR_REFUSALS = 'refused_messages.json'
# Wall seconds between the watch's looks at the master and at this node (Session.watch).
WATCH_EVERY_S = 0.5


# Wall seconds the robot has to be commanded to set off in the stop check (5 s of sim time).
SET_OFF_WALL_S = 120.0
# Wall seconds sensors has to see an image and a scan, and lockstep its connections.
SENSORS_WALL_S = 30.0
LOCKSTEP_WALL_S = 10.0


def sim_wall_s(sim_seconds):
    """Wall seconds the grader waits for sim_seconds of sim time before it counts as stalled:
    lockstep can make sim time far slower than the wall's when the nodes are slow."""
    return 60.0 + 20.0 * sim_seconds


def run_wall_bound(trials, timeout, world_timeout=120.0, chaser_timeout=30.0):
    """Wall seconds the rubric run can take with every step as slow as the session lets it be:
    the sum of each step's own bound. The world and ball_chaser.launch come up at most three
    times (its first start, and two starts again when the guess of drive_bot was wrong or its
    service is not the course's), each within its bound and a last look at its service; drive_bot
    is called four times; each trial, and the stop check's three waits, within their wall bounds."""
    bring_up = (3 * (world_timeout + chaser_timeout + probe.HEADER_PROBE_S) + 4 * DRIVE_CALL_S
                + SENSORS_WALL_S + LOCKSTEP_WALL_S)
    stop_check = SET_OFF_WALL_S + sim_wall_s(0.5) + sim_wall_s(REACT_S + WATCH_S)
    return bring_up + max(trials, 1) * sim_wall_s(timeout) + stop_check


def stability_advisory(spec):
    """The report's advisory line: would the robot stand, with the numbers behind it."""
    from flatsim.stability import assess
    stability, why = assess(spec)
    if stability is None:
        return 'robot stability: not judged: %s' % why
    return 'robot stability: %s' % stability.describe()


@dataclass
class SessionSpec:
    overlay_env: dict              # the environment of the built overlay (sourced in the sandbox)
    overlay_root: str
    run_scratch: str               # the only folder the submission's nodes may write
    out_dir: str                   # report folder (the submission cannot write it)
    robot_package: str
    chaser_package: str
    trials: int = 3
    seed: int = 0
    timeout: float = 60.0          # sim seconds per trial
    reach: float = placement.REACH_GAP_M  # m from the robot's outline to the ball's surface
    pass_rate: float = 0.8         # share of trials that must reach the ball
    isolate: bool = True
    lockstep: bool = True          # chase with sim time waiting for the nodes
    master_port: int = 11311       # the session's network namespace is its own: no other master there
    world_timeout: float = 120.0   # wall seconds for the world to come up
    chaser_timeout: float = 30.0   # wall seconds for drive_bot's service to appear
    chaser_launches_world: bool = False   # ball_chaser.launch includes world.launch
    worlds: int = 1                # worlds the chase trials are shared among (see grading/worlds.py)
    logs_dir: str = ''             # default out_dir/logs
    extra_world: dict = None       # in an extra world: what the session's own world found (TrialWorld)
    # Started before the build: the master comes up meanwhile, then the session reads
    # {"overlay_env": {...}, "chaser_launches_world": ...} on stdin once the workspace is
    # built (nothing: it was not).
    await_build: bool = False
    confinement: dict = None       # sandbox.Confinement.as_json(): uid, limits, cgroups
    grader_dir: str = ''           # the grader's own folder: prepared launch files go here
    caches_dir: str = ''           # empty folder for the simulator's writable numba caches


def launch_excerpt(path, out_dir):
    """The decisive lines of a launch log, for an item's evidence, each with its place in the
    report folder (logs/...)."""
    return evidence.log_lines(path, os.path.relpath(path, out_dir))


def launch_processes(path, start=0):
    """(started, died): the process names roslaunch reports in its log, from byte start on."""
    import re
    try:
        with open(path, errors='replace') as stream:
            stream.seek(start)
            text = stream.read()
    except OSError:
        return set(), set()
    return (set(re.findall(r'process\[([\w.-]+)\]: started', text)),
            set(re.findall(r'\[([\w.-]+)\] process has died', text)))


class WorldLaunch(ProcessGroup):
    """The launch of the submission's world; alive while the launch and the grader's simulator
    (simulator, a ProcessGroup, set once it runs: bring_up_simulator) both are."""
    SIMULATOR = 'flatsim'

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.simulator = None
        self.simulator_died = False

    def alive(self):
        if not super().alive():
            return False
        # A simulator stopped (its group emptied) is over too.
        self.simulator_died = self.simulator is not None and not (self.simulator.procs
                                                                  and self.simulator.alive())
        return not self.simulator_died


GUARDS = {}                     # topic -> the SimulatorGuard its messages pass
SERVICE_GUARDS = {}             # service prefix -> the SimulatorGuard that says where to call


def guard_topics(topics, guard):
    """From now on, the messages of these topics reach this process's callbacks only through
    guard.receive. rospy hands each new connection the subscriber's receive_callback as it is
    when the connection is made, which can be before a Subscriber's constructor returns: so
    the class's own is replaced, once, before any subscription."""
    from rospy.topics import _SubscriberImpl
    if not hasattr(_SubscriberImpl, 'unguarded_receive_callback'):
        _SubscriberImpl.unguarded_receive_callback = _SubscriberImpl.receive_callback

        def receive_callback(impl, msgs, connection):
            deliver = impl.unguarded_receive_callback
            guard = GUARDS.get(impl.resolved_name)
            if guard is None:
                deliver(msgs, connection)
            else:
                guard.receive(impl.resolved_name, deliver, msgs, connection)
        _SubscriberImpl.receive_callback = receive_callback
    for topic in topics:
        GUARDS[topic] = guard


def guard_services(prefixes, guard):
    """From now on, this process calls the services under these prefixes where guard.address_for
    says. rospy asks the master at each call, and the master answers with whoever registered
    the name last, which may have given it back by the time anyone looks."""
    from rospy.impl.tcpros_service import ServiceProxy
    if not hasattr(ServiceProxy, 'unguarded_service_uri'):
        ServiceProxy.unguarded_service_uri = ServiceProxy._get_service_uri

        def service_uri(proxy, request):
            guard = next((guard for prefix, guard in SERVICE_GUARDS.items()
                          if proxy.resolved_name.startswith(prefix)), None)
            try:
                given = proxy.unguarded_service_uri(request)
            except rospy.ServiceException:
                # Nobody serves it now: a node that took the name over and then let it go.
                given = None
            return given if guard is None else guard.address_for(proxy.resolved_name, given)
        ServiceProxy._get_service_uri = service_uri
    for prefix in prefixes:
        SERVICE_GUARDS[prefix] = guard


def tampered(found):
    """The error of a verdict that SimulatorGuard.tampering() found reasons not to trust."""
    return '%s: %s' % (TAMPERED, '; '.join(found[:TAMPERING_SHOWN]))


class SimulatorGuard:
    """The model states and sim time count only from the simulator the grader started.

    Any node of the submission can publish on /gazebo/model_states or /clock, or
    serve /gazebo/set_model_state, and so fake a chase. The grader takes messages
    on those topics only over its connection to the simulator node
    (/flatsim), whose address the master gave when the world came up (pin()):
    each connection's endpoint is the publisher address this node connected to,
    which a publisher cannot choose by what it writes in its header. Messages from
    anywhere else are dropped and counted, and tampering() names them, with any
    other publisher of those topics and any service of the simulator's that
    another node took over, before a chase or a stop is judged. The master takes
    any caller's word for its name, so a service the simulator served when the
    world came up must also still be served from the address it had then; and the
    grader calls it there, whatever the master says at the time of a call.
    """
    SIMULATOR = '/flatsim'
    MOVES_TOPIC = SIMULATOR + '/model_moves'
    TOPICS = (chase_graph.MODEL_STATES_TOPIC, chase_graph.SIM_NAMESPACE + '/link_states', '/clock',
              MOVES_TOPIC)
    # Names only a simulator registers under: flatsim's, and gzserver's in Gazebo.
    NAMES = (SIMULATOR, chase_graph.SIM_NAMESPACE)
    SERVICE_PREFIXES = (chase_graph.SIM_NAMESPACE + '/', SIMULATOR + '/')

    def __init__(self, master):
        self.master = master
        self.uri = None
        self.pinned = False
        self.services = {}              # the simulator's services, pinned: name -> address
        self.looked = 0.0
        self.refused = {}               # (topic, publisher) -> messages dropped
        self.redirected = set()         # (service, address) the master gave at a call, not pinned
        self.claims = []                # nodes a launch of the submission names as the simulator
        self.lock = threading.Lock()
        guard_topics(self.TOPICS, self)
        guard_services(self.SERVICE_PREFIXES, self)

    def receive(self, topic, deliver, msgs, connection):
        if connection.endpoint_id == self.simulator_uri():
            deliver(msgs, connection)
        else:
            self.refuse(topic, connection, len(msgs))

    def simulator_uri(self):
        """The simulator's address: pinned once the world is up, else the master's answer."""
        if self.pinned or self.uri is not None:
            return self.uri
        # Each topic's messages come on a thread of their own: the first to ask looks it up,
        # the others wait for its answer rather than take none for one.
        with self.lock:
            if self.uri is None and time.monotonic() - self.looked >= LOOKUP_EVERY_S:
                self.looked = time.monotonic()
                self.uri = self.lookup()
            return self.uri

    def lookup(self):
        try:
            # A master client of its own: this runs on rospy's receiving threads too, and one
            # client's connection is not to be shared among threads.
            return rosgraph.Master(self.master.caller_id).lookupNode(self.SIMULATOR)
        except Exception:  # noqa: BLE001 - no simulator (yet), or a master that does not answer
            return None

    def pin(self):
        """The simulator is up: from now on its address, and its services', must not change."""
        self.uri, self.pinned = self.lookup(), True
        self.services = self.served_as_simulator()

    def address_for(self, service, given):
        """Where to call one of the simulator's services: where it was when the world came up."""
        pinned = self.services.get(service)
        if pinned is None:
            if given is None:
                raise rospy.ServiceException('service [%s] unavailable' % service)
            return given
        if given is not None and given != pinned:
            with self.lock:
                self.redirected.add((service, given))
        return pinned

    def served_as_simulator(self):
        """{service: its address} of the services the master lists under the simulator's name."""
        try:
            _publishers, _subscribers, services = self.master.getSystemState()
            return {service: self.master.lookupService(service) for service, nodes in services
                    if service.startswith(self.SERVICE_PREFIXES) and nodes == [self.SIMULATOR]}
        except Exception:  # noqa: BLE001 - a master that no longer answers: the run has ended
            return {}

    def node_at(self, address):
        """The node that takes connections at a service's address: a node's topics and services
        share one port, which it gives for the /rosout that every node publishes."""
        wanted = rospy.core.parse_rosrpc_uri(address)
        try:
            publishers, _subscribers, _services = self.master.getSystemState()
        except Exception:  # noqa: BLE001 - a master that no longer answers: the run has ended
            return 'an unknown node'
        for node in dict(publishers).get('/rosout', []):
            try:
                node_api = probe.node_proxy(self.master.lookupNode(node), NODE_ANSWER_S)
                _code, _text, protocol = node_api.requestTopic(self.master.caller_id, '/rosout',
                                                               [['TCPROS']])
                if tuple(protocol[1:3]) == wanted:
                    return node
            except Exception:  # noqa: BLE001 - a node that does not answer is not the one
                continue
        return 'an unknown node'

    def refuse(self, topic, connection, count):
        who = '%s (%s)' % (getattr(connection, 'callerid_pub', None) or '?', connection.endpoint_id)
        with self.lock:
            self.refused[(topic, who)] = self.refused.get((topic, who), 0) + count

    def tampering(self):
        """What another node did in the simulator's place, one line each; [] if nothing."""
        with self.lock:
            found = list(self.claims) + ['%d message%s on %s from %s, which is not the simulator'
                     % (count, '' if count == 1 else 's', topic, who)
                     for (topic, who), count in sorted(self.refused.items())]
            redirected = sorted(self.redirected)
        found += ['at a call of %s the master gave the address of %s (%s), not the simulator\'s'
                  % (service, self.node_at(address), address) for service, address in redirected]
        for name in self.NAMES[1:]:
            try:
                uri = rosgraph.Master(self.master.caller_id).lookupNode(name)
            except Exception:  # noqa: BLE001 - no node of that name
                continue
            found.append('a node registered under the simulator\'s name %s (%s)' % (name, uri))
        try:
            publishers, _subscribers, services = self.master.getSystemState()
        except Exception:  # noqa: BLE001 - a master that no longer answers: the run has ended
            return found
        for topic, nodes in publishers:
            if topic in self.TOPICS:
                found += ['%s publishes on %s, which only the simulator may' % (node, topic)
                          for node in nodes if node != self.SIMULATOR]
        for service, nodes in services:
            if service.startswith(self.SERVICE_PREFIXES):
                found += ['%s serves %s, the simulator\'s service' % (node, service)
                          for node in nodes if node != self.SIMULATOR]
        if self.pinned and self.uri is not None and self.lookup() != self.uri:
            found.append('another node took the simulator\'s name %s (now at %s)'
                         % (self.SIMULATOR, self.lookup()))
        for service, address in sorted(self.served_as_simulator().items()):
            if self.services.get(service, address) != address:
                found.append('%s is served by %s (%s), registered under the simulator\'s name'
                             % (service, self.node_at(address), address))
        return found


class CallCounter:
    """Serves /grader/command_robot: records each request of process_image, forwards it to drive_bot."""

    def __init__(self, clock):
        DriveToTarget = course_service.course_drive_to_target()
        self.srv_type = DriveToTarget
        self.clock = clock
        self.calls = trials.RollingLog(CALLS_KEPT)     # (sim time, linear_x, angular_z)
        self.forwarding = False
        self.server = None
        self.advertise()

    def advertise(self):
        self.close()
        self.server = rospy.Service(submission.PROXY_SERVICE, self.srv_type, self.handle)

    def close(self):
        if self.server is not None:
            self.server.shutdown()
            self.server = None

    def handle(self, req):
        self.calls.append((self.clock.now(), req.linear_x, req.angular_z))
        if not self.forwarding:
            return self.srv_type._response_class('held while drive_bot is tested')
        try:
            # A master client of its own: each caller's connection has a thread of its own.
            uri = rosgraph.Master(rospy.get_name()).lookupService(submission.COURSE_SERVICE)
            return probe.call_service(uri,
                                      submission.COURSE_SERVICE, self.srv_type, req, FORWARD_S)
        except (probe.ProbeError, rosgraph.masterapi.Error, OSError) as error:
            raise rospy.ServiceException('drive_bot did not answer: %s' % error) from None


class ModelMoves:
    """The models moved through the simulator's API while a trial runs, as flatsim says on
    ~model_moves (only the simulator's own messages pass the guard)."""

    def __init__(self):
        self.watching = False
        self.moves = []
        self.own = 0                    # the grader's own moves in this watch
        self.own_seen = 0               # the moves flatsim said the grader made in it
        self.lock = threading.Lock()
        rospy.Subscriber(SimulatorGuard.MOVES_TOPIC, String, self.on_move, queue_size=MOVES_KEPT)

    def begin(self):
        with self.lock:
            self.watching, self.moves, self.own, self.own_seen = True, [], 0, 0

    def made(self):
        """The grader moved a model itself."""
        with self.lock:
            self.own += 1

    def on_move(self, msg):
        try:
            said = json.loads(msg.data)
            move = trials.Move(float(said['time']), str(said['by']), str(said['through']),
                               str(said['target']))
        except (ValueError, KeyError, TypeError):
            return
        with self.lock:
            if self.watching:
                self.own_seen += move.by == rospy.get_name()
                if len(self.moves) < MOVES_KEPT:
                    self.moves.append(move)

    def end(self):
        """The moves of this watch that the grader did not make, once flatsim has said the
        grader's own (or MOVES_SEEN_S has passed)."""
        wait_until(lambda: self.own_seen >= self.own, [], MOVES_SEEN_S, poll_s=POLL_S)
        with self.lock:
            self.watching = False
            return trials.moves_not_made_by(self.moves, rospy.get_name(), self.own)


def moved(moves, jump, robot):
    """The error of a trial in which models moved as no chase moves them; '' if none did."""
    found = [move.describe() for move in moves[:MOVES_SHOWN]]
    if len(moves) > MOVES_SHOWN:
        found.append('%d more move%s' % (len(moves) - MOVES_SHOWN,
                                         '' if len(moves) - MOVES_SHOWN == 1 else 's'))
    if jump is not None:
        found.append(jump.describe(robot))
    return '%s: %s' % (MOVED, '; '.join(found)) if found else ''


class NotBuilt(Exception):
    """The session was started before the build, which did not end in a workspace to run."""


class SimClock:
    """Sim time from /clock, kept here so it is right whatever the node was started with."""

    def __init__(self):
        self.time = None
        self.after_reset = False
        self.changed = threading.Condition()
        rospy.Subscriber('/clock', Clock, self.on_clock, queue_size=10)

    def begin_run(self):
        """Sim time is about to go back to 0: until it has, report 0 and ignore later stamps,
        which may still be on their way from before the reset."""
        with self.changed:
            self.after_reset = True
            self.time = 0.0

    def on_clock(self, msg):
        stamp = msg.clock.to_sec()
        with self.changed:
            if self.after_reset:
                if stamp > NEW_RUN_STAMP_S:
                    return
                self.after_reset = False
            self.time = stamp
            self.changed.notify_all()

    def started(self):
        """False between begin_run() and the first /clock of the new run."""
        return not self.after_reset

    def now(self):
        return self.time if self.time is not None else 0.0

    def wait(self, seconds, alive, wall_limit=None):
        """Wait for seconds of sim time; False if the launches died or sim time stalled."""
        start = self.now()
        wall_deadline = time.monotonic() + (wall_limit or sim_wall_s(seconds))
        with self.changed:
            while self.now() - start < seconds:
                if not alive() or time.monotonic() > wall_deadline:
                    return False
                self.changed.wait(0.2)
        return True


class FrameWatch:
    """Looks at the camera's frames early in each trial: did the ball show (a pure-white pixel)?

    Only the first FRAME_WATCH_S of sim time, or until the ball has shown: a frame of the
    course camera is 2 MB, and the grader must not cost the chase its speed.
    """

    def __init__(self, clock):
        self.clock = clock
        self.subscriber = None
        self.armed = False
        self.frames = self.white_frames = 0
        self.lock = threading.Lock()

    def subscribe(self):
        """Before the trial starts, so that the connection is made by its first frame."""
        self.frames = self.white_frames = 0
        self.armed = False
        self.subscriber = rospy.Subscriber(CAMERA_TOPIC, Image, self.on_image, queue_size=1,
                                           buff_size=1 << 24)

    def begin(self):
        """The trial has started: frames of the new run count from now on."""
        self.armed = True

    def on_image(self, msg):
        if not (self.armed and self.clock.started()) or msg.header.stamp.to_sec() > FRAME_WATCH_S:
            return                      # a frame from before the reset
        if self.clock.now() > FRAME_WATCH_S:
            self.stop()
            return
        white = trials.has_white_pixel(msg.data, msg.width, msg.height, msg.step, msg.encoding)
        if white is None:
            return
        with self.lock:
            self.frames += 1
            self.white_frames += int(white)
        if white:
            self.stop()

    def stop(self):
        with self.lock:
            subscriber, self.subscriber = self.subscriber, None
        if subscriber is not None:
            subscriber.unregister()


class Session:
    def __init__(self, spec):
        self.spec = spec
        self.grade = rubric.Grade(spec.overlay_root, seed=spec.seed)
        self.logs = spec.logs_dir or os.path.join(spec.out_dir, 'logs')
        os.makedirs(self.logs, exist_ok=True)
        self.env = dict(os.environ)
        self.env.pop('ROS_IP', None)
        self.env.update(QUICK_START, ROS_MASTER_URI='http://localhost:%d' % spec.master_port,
                        ROS_HOSTNAME='localhost', ROS_HOME=os.path.join(self.logs, 'ros'))
        self.confinement = Confinement.from_json(spec.confinement) if spec.confinement else None
        self.log_limit = self.confinement.limits.log if self.confinement else Limits().log
        # This node's own log file, which what the submission sends it can make write, is
        # rotated at the log limit.
        self.env['ROS_PYTHON_LOG_CONFIG_FILE'] = logging_config(
            os.path.join(spec.grader_dir or self.logs, 'python_logging_%d.conf' % os.getpid()),
            self.log_limit)
        os.environ.update(self.env)
        self.use_overlay_env(spec.overlay_env)
        self.sandbox = self.make_sandbox() if spec.isolate else None
        self.open_logs = {}             # id(group) -> [CappedLog]
        self.prepared = 0               # launch files prepared so far, each set in a folder of its own
        self.world_copies = 0           # the same for the world's copies
        self.model_paths = []           # where the includes of the grader's copy of the world lie
        self.originals = {}             # without a sandbox: launch file -> a copy of it as built
        # roscore logs its whole environment into logs/ros, which is part of the report.
        self.core = ProcessGroup(dict(allowed_environment(self.env), HOME=self.env.get('HOME', '/')),
                                 stop_timeout=STOP_GRACE_S)
        self.core_box = None            # core.Core: roscore's sandbox, when the run has one
        self.core_log = os.path.join(self.logs, 'roscore.log')
        self.messages = MessageLimit(sender=self.sender)
        # Why the watch ended the run (the master ended, this node was shut down), or None.
        self.ended_by = None
        self.finished = False
        self.watch_lock = threading.Lock()
        # Nothing of the submission needs a clean shutdown: a short grace, then SIGKILL.
        self.world = WorldLaunch(stop_timeout=STOP_GRACE_S)
        self.chaser = ProcessGroup(stop_timeout=STOP_GRACE_S)
        self.simulator = ProcessGroup(stop_timeout=STOP_GRACE_S)
        self.simulator_sandbox = None
        self.launch_reads = 0
        self.world_notes = []
        self.master = rosgraph.Master('/grade_probe')
        self.world_log = os.path.join(self.logs, 'world_launch.log')
        self.chaser_log = os.path.join(self.logs, 'ball_chaser_launch.log')
        self.launches_as(spec.chaser_launches_world)
        self.models = None
        self.cmd = trials.RollingLog(COMMANDS_KEPT)    # (sim time, linear.x, angular.z) on /cmd_vel
        self.guard = SimulatorGuard(self.master)
        self.robot = self.ball = None
        self.world_map = None

    def launches_as(self, chaser_launches_world):
        self.spec.chaser_launches_world = chaser_launches_world
        if chaser_launches_world:
            # One launch: the world's log and process group are the chaser's.
            self.world_log, self.chaser = self.chaser_log, self.world

    def use_overlay_env(self, overlay_env):
        """The environment of the built workspace, for the submission's launches."""
        self.overlay_env = dict(overlay_env)
        self.student_env = dict(overlay_env)
        self.student_env.update(QUICK_START, ROS_MASTER_URI=self.env['ROS_MASTER_URI'],
                                ROS_HOSTNAME='localhost')
        self.student_env.pop('ROS_IP', None)

    # -- processes ---------------------------------------------------------------------
    def make_sandbox(self):
        """The run's sandbox: the built workspace read-only, the run folder writable."""
        import flatsim
        stand_ins = [pair for path in flatsim.__path__
                     # catkin's devel space extends the package's __path__ to its sources.
                     for pair in cache_stand_ins(path, self.spec.caches_dir)]
        if self.confinement.switch_user:
            hand_over(self.spec.caches_dir, self.confinement.uid, self.confinement.gid)
        return Sandbox(self.spec.run_scratch,
                       visible=environment_paths(self.env) + [self.spec.overlay_root],
                       stand_ins=stand_ins, confinement=self.confinement)

    def start_submission_launch(self, group, package, launch_file, log_path, args=()):
        cmd = ['roslaunch', package, launch_file] + list(args)
        env = dict(self.student_env)
        if self.spec.isolate:
            cmd, env = self.sandbox.wrap(cmd, env)
        group.env = env
        log = CappedLog(log_path, self.log_limit)
        try:
            group.start(cmd, log)
        finally:
            log.started()
        self.open_logs.setdefault(id(group), []).append(log)

    def prepare_launch_files(self, package_dir, remap=False, keep=()):
        """The package's launch files prepared for a headless run (submission.prepare_launch_files),
        shown in place of the originals to every launch from now on; a later preparation of the
        package replaces this one."""
        self.prepared += 1
        copies = os.path.join(self.spec.grader_dir or self.logs, 'launch', str(self.prepared))
        os.makedirs(copies, mode=0o755)
        top = package_dir.rstrip('/') + '/'
        if self.sandbox is None:
            # No sandbox to show the copies in place: they replace the files (never what a link
            # there points at), the originals kept to start from next time.
            for path, original in self.originals.items():
                if path.startswith(top):
                    shutil.copyfile(original, path + '.grading')
                    os.replace(path + '.grading', path)
        changes = submission.prepare_launch_files(package_dir, copies, remap, keep)
        if self.sandbox is not None:
            self.sandbox.overlays = {path: copy for path, copy in self.sandbox.overlays.items()
                                     if not path.startswith(top)}
            self.sandbox.overlays.update(changes.copies)
            return changes
        for path, copy in changes.copies.items():
            if path not in self.originals:
                self.originals[path] = copy + '.original'
                shutil.copyfile(path, self.originals[path])
            shutil.copyfile(copy, path + '.grading')
            os.replace(path + '.grading', path)
        return changes

    def copy_world(self, path, notes):
        """The grader's own copy of the world file the simulator names and of the models it
        includes, made by the submission's sandbox and read as data (worldcopy.py); '' and a
        note when there is none."""
        self.model_paths = []
        if not path:
            return ''
        self.world_copies += 1
        # Each world's copies apart: the run folder is every world's.
        relative = os.path.join('world' if self.spec_world_number() == 1
                                else 'world_%d' % self.spec_world_number(), str(self.world_copies))
        cmd, env = [sys.executable, '-m', 'chase_tools.grading.worldcopy', path,
                    os.path.join(self.spec.run_scratch, relative)], dict(self.student_env)
        if self.sandbox is not None:
            cmd, env = self.sandbox.wrap(cmd, env)
        said = run_captured(cmd, env=env, timeout=WORLD_COPY_S, keep=WORLD_COPY_LOG).stdout.strip()
        taken = worldcopy.snapshot(self.spec.run_scratch, relative,
                                   os.path.join(self.spec.grader_dir or self.logs, relative), path)
        if said or taken.left_out:
            notes.append('of the world file %s and the models it includes, not read: %s'
                         % (path, '; '.join(said.splitlines()[:5] + taken.left_out[:5])))
        self.model_paths = taken.model_paths
        return taken.world_file

    # -- the grader's simulator -----------------------------------------------------------
    def bring_up_simulator(self, package, launch_file):
        """Start the grader's own simulator as the submission's launch would have started it
        (simulator.py): its world and parameters read by the sandbox (launchread.py), the world
        copied (copy_world). The guard is pinned to it before any node of the submission runs.
        Sets world_file, model_paths and world_notes."""
        notes = self.world_notes = []
        asked = self.read_launch(package, launch_file, notes)
        self.guard.claims = ['%s starts the node %s (%s/%s) under the simulator\'s name'
                             % (launch_file, claim['node'], claim['package'], claim['type'])
                             for claim in asked['claims']]
        simulators = asked['simulators']
        if not simulators:
            notes.append('%s starts no simulator (gazebo_ros\'s empty_world.launch, gzserver or '
                         'gazebo): the grader\'s simulator runs an empty world' % launch_file)
        elif len(simulators) > 1:
            notes.append('%s starts %d simulators (%s); the grader\'s simulator runs the first\'s '
                         'world' % (launch_file, len(simulators),
                                    ', '.join(entry['node'] for entry in simulators)))
        chosen = simulators[0] if simulators else {'params': {}, 'args': []}
        self.world_file = self.copy_world(launchread.world_of(chosen), notes)
        if self.world_file:
            simulator.make_readable(os.path.dirname(self.world_file))
        self.start_simulator(chosen['params'], asked['use_sim_time'])
        if not self.spec.extra_world:
            who = ('as uid %d in a sandbox of its own' % self.simulator_sandbox.confinement.uid
                   if self.simulator_sandbox is not None else 'without a sandbox (--no-isolation)')
            self.grade.notes.append('the grader ran the simulator itself (flatsim, see %s), %s, '
                                    'with the world %s gives it: %s' % (
                                        self.log_label(os.path.join(self.logs, 'simulator.log')), who,
                                        launch_file, os.path.basename(self.world_file) or 'none'))

    def read_launch(self, package, launch_file, notes):
        """What the launch asks of the simulator (launchread.parse), read in the sandbox; no
        simulator, and a note, if it could not be read."""
        self.launch_reads += 1
        # The run folder is every world's.
        relative = 'launch_read_%d_%d.json' % (self.spec_world_number(), self.launch_reads)
        cmd = [sys.executable, '-m', 'chase_tools.grading.launchread', package, launch_file,
               os.path.join(self.spec.run_scratch, relative)]
        env = dict(self.student_env)
        if self.sandbox is not None:
            cmd, env = self.sandbox.wrap(cmd, env)
        said = run_captured(cmd, env=env, timeout=LAUNCH_READ_S, keep=WORLD_COPY_LOG).stdout.strip()
        try:
            return launchread.parse(read_beneath(self.spec.run_scratch, relative,
                                                 launchread.READ_LIMIT))
        except (OSError, launchread.LaunchReadError) as error:
            notes.append('%s could not be read for its simulator: %s' % (
                launch_file, '; '.join(said.splitlines()[-3:]) or error))
            return {'simulators': [], 'claims': [], 'use_sim_time': None}

    def start_simulator(self, params, use_sim_time):
        """Start flatsim with params as its private parameters, the grader's copy of the world,
        and no studio; once it serves Gazebo's API, pin the guard to it."""
        import roslib.packages
        name = '/' + simulator.NODE_NAME
        for key, value in sorted(params.items()):
            self.master.setParam('%s/%s' % (name, key), value)
        self.master.setParam(name + '/world_name', self.world_file or '')
        self.master.setParam(name + '/studio', False)
        self.master.setParam('/use_sim_time', use_sim_time if isinstance(use_sim_time, bool) else True)
        program = roslib.packages.find_node('flatsim', 'simulator')[0]
        cmd = [program, '__name:=' + simulator.NODE_NAME]
        env = dict(self.env, GAZEBO_MODEL_PATH=os.pathsep.join(self.model_paths))
        if self.sandbox is not None:
            box = self.simulator_sandbox_for()
            # The simulator takes no message larger than the grader's node does.
            cmd = [sys.executable, '-m', 'chase_tools.grading.message_limit',
                   os.path.join(box.scratch, SIMULATOR_REFUSALS)] + cmd
            cmd, env = box.wrap(cmd, env)
            self.sandbox.overlays.update(simulator.standby_overlays(
                os.path.join(self.spec.grader_dir or self.logs, 'standby')))
        self.simulator.env = env
        log = CappedLog(os.path.join(self.logs, 'simulator.log'), self.log_limit)
        try:
            self.simulator.start(cmd, log)
        finally:
            log.started()
        self.open_logs.setdefault(id(self.simulator), []).append(log)
        self.world.simulator = self.simulator
        # Gazebo's API, then ~set_lockstep: the last service flatsim registers.
        wait_until(lambda: chase_graph.LOCKSTEP_SERVICE in self.guard.served_as_simulator(),
                   [self.simulator], self.spec.world_timeout, poll_s=POLL_S)
        self.guard.pin()

    def simulator_sandbox_for(self):
        """The simulator's sandbox (simulator.py): its own folder writable, the workspace and the
        world's copy read-only, numba's caches writable copies."""
        if self.simulator_sandbox is None:
            import flatsim
            folder = os.path.join(self.spec.grader_dir or self.logs, 'simulator')
            os.makedirs(folder, mode=0o700)
            confinement = simulator.confinement(folder, self.confinement)
            scratch = os.path.join(folder, 'run')
            caches = os.path.join(folder, 'caches')
            os.makedirs(caches, mode=0o700)
            stand_ins = [pair for path in flatsim.__path__ for pair in cache_stand_ins(path, caches)]
            visible = environment_paths(self.env)
            if self.world_file:
                visible.append(os.path.dirname(self.world_file))
            visible += [path for path in self.model_paths if path not in visible]
            self.simulator_sandbox = Sandbox(scratch, visible=visible, stand_ins=stand_ins,
                                             confinement=confinement)
            self.simulator_sandbox.prepare()
            if confinement.switch_user:
                hand_over(caches, confinement.uid, confinement.gid)
        return self.simulator_sandbox

    def stop_simulator(self):
        """Stop the grader's simulator, last; a note if it had ended before (its log says why)."""
        for proc in self.simulator.procs:
            if proc.poll() is not None:
                self.grade.notes.append('the grader\'s simulator had ended before the grader '
                                        'stopped it (exit status %d); see logs/simulator.log'
                                        % proc.returncode)
                continue
            for pid in (sandbox_children(proc.pid)[:1] if self.simulator_sandbox else [proc.pid]):
                try:
                    os.kill(pid, signal.SIGINT)
                except ProcessLookupError:
                    pass
        self.finish_stopping([(self.simulator, 'the simulator')])

    def stop_launch(self, group, name):
        """Stop a launch of the submission: roslaunch first, which stops its nodes, then its
        sandbox. Says in the notes if it had ended by itself, or left processes behind."""
        self.stop_launches([(group, name)])

    def stop_launches(self, launches):
        """Stop launches [(group, name)] together: each roslaunch gets SIGINT at once, and they
        stop their nodes side by side, within one grace time."""
        self.ask_to_stop_all(launches)
        self.finish_stopping(launches)

    def ask_to_stop_all(self, launches):
        for group, name in launches:
            self.ask_to_stop(group, name)

    def finish_stopping(self, launches):
        deadline = time.monotonic() + STOP_GRACE_S
        for group, _name in launches:
            for proc in group.procs:
                try:
                    proc.wait(max(0.0, deadline - time.monotonic()))
                except subprocess.TimeoutExpired:
                    pass
        for group, _name in launches:
            try:
                group.stop()
            except OSError:
                pass
            self.close_logs(group)

    def ask_to_stop(self, group, name):
        """SIGINT to the launch's roslaunch, inside its sandbox; notes on how it was found."""
        for proc in group.procs:
            if proc.poll() is not None:
                log = self.chaser_log if name == 'ball_chaser.launch' else self.world_log
                self.grade.notes.append('%s had ended by itself before the grader stopped it (exit '
                                        'status %d); see %s' % (name, proc.returncode,
                                                                self.log_label(log)))
                continue
            if self.sandbox is None:
                continue
            inside = sandbox_children(proc.pid)
            if len(inside) > 1:
                self.grade.notes.append('%s left %d process%s running outside roslaunch (%s); '
                                        'they were killed with its sandbox' % (
                                            name, len(inside) - 1, '' if len(inside) == 2 else 'es',
                                            ', '.join(process_name(pid) for pid in inside[1:])))
            for pid in inside[:1]:
                try:
                    os.kill(pid, signal.SIGINT)
                except ProcessLookupError:
                    pass

    def close_logs(self, group):
        for log in self.open_logs.pop(id(group), []):
            cap = log.close()
            if cap.cut:
                self.grade.notes.append('%s: %s cut of %s written (the first and last %s '
                                        'kept)' % (self.log_label(log.path), size_text(cap.cut),
                                                   size_text(cap.total), size_text(cap.keep // 2)))

    def stop_all(self):
        """Stop the extra worlds, this world's launches and the master, side by side."""
        with self.watch_lock:
            # The master's end is no longer news.
            self.finished = True
        launches = [(self.chaser, 'ball_chaser.launch')]
        if self.world is not self.chaser:
            launches.append((self.world, 'world.launch'))
        # A node that finds the master gone on its way out needs no answer from it.
        core = threading.Thread(target=self.stop_core, daemon=True)
        extra = threading.Thread(target=self.extra_worlds.stop if self.extra_worlds else None,
                                 daemon=True)
        extra.start()
        self.ask_to_stop_all(launches)
        core.start()
        self.finish_stopping(launches)
        extra.join()
        self.stop_simulator()
        if self.extra_worlds is not None:
            self.grade.notes.extend(self.extra_worlds.take_notes())
        # The sandbox's processes are every world's: the session's own world ends them last.
        if self.confinement is not None and self.spec.isolate and not self.spec.extra_world:
            left = end_sandbox(self.confinement)
            if left:
                self.grade.notes.append('%d process%s of the submission still ran after its launches '
                                        'had ended (%s); they were killed' % (
                                            len(left), '' if len(left) == 1 else 'es', ', '.join(left)))
        core.join()

    def stop_core(self):
        try:
            self.core.stop()
        except OSError:
            pass
        self.close_logs(self.core)
        self.grade.notes.extend(self.messages.notes())
        if self.simulator_sandbox is not None:
            try:
                record = read_beneath(self.simulator_sandbox.scratch, SIMULATOR_REFUSALS, RECORD_LIMIT)
            except OSError:
                record = None           # it refused nothing
            if record is not None:
                # The grader's node, sent the same, may have named the sender while it ran.
                self.grade.notes.extend(simulator_notes(
                    record.decode(errors='replace'),
                    lambda topic, port: self.messages.names.get((topic, port)) or self.sender(topic, port)))
        if self.core_box is None:
            return
        self.core_box.end()
        for relative, cap in self.core_box.copy_logs(os.path.join(self.logs, 'ros', 'log')):
            full = self.core_box.limits.file_size
            self.grade.notes.append('%s: %s cut of %s written (the first and last %s kept)%s' % (
                self.log_label(os.path.join(self.logs, 'ros', 'log', relative)), size_text(cap.cut),
                size_text(cap.total), size_text(cap.keep // 2),
                '; roscore\'s file size limit of %s ended it there' % size_text(full)
                if cap.total >= full else ''))

    # -- the run -------------------------------------------------------------------------
    def run(self):
        steps = [('master', self.start_master)]
        if self.spec.await_build:
            steps.append(('waiting for the build', self.await_build))
        steps += [('world_launches', self.check_world),
                 ('sensors', self.check_sensors), ('ball_chaser', self.start_chaser),
                 ('drive_bot_service', self.check_drive_bot), ('lockstep', self.enable_lockstep),
                 ('chase', self.run_trials),
                 # It deletes the ball: after this world's trials, while the others finish theirs.
                 ('stops_without_ball', self.check_stop),
                 ('chase, every world\'s trials in', self.finish_trials),
                 ('process_image_calls', self.check_process_image)]
        self.started = time.monotonic()
        signal.signal(signal.SIGINT, self.on_sigint)
        name = 'the start'
        try:
            try:
                for name, step in steps:
                    self.say('%s ...' % name)
                    self.step = name
                    step()
                self.step = None
            except KeyboardInterrupt:
                if self.ended_by is None:
                    raise
                self.grade.notes.append('the run ended during %s: %s' % (name, self.ended_by))
                self.grade.not_run(self.ended_by)
        except NotBuilt:
            self.grade.not_run('the build failed')
        except Exception as error:  # noqa: BLE001 - whatever went wrong is a failed item, not a crash
            import traceback
            # Whatever the run asked of a master that has gone fails: the master's end is why.
            trouble = self.core_trouble() if self.core.procs else ''
            if trouble:
                self.grade.notes.append('the run ended during %s: %s' % (name, trouble))
                self.grade.not_run(trouble)
            self.grade.notes.append('the run stopped early: %s: %s' % (type(error).__name__, error))
            self.grade.not_run('the run stopped early (%s: %s)' % (type(error).__name__, error))
            traceback.print_exc()
        finally:
            with self.watch_lock:
                self.finished = True
            self.say('stopping')
            self.stop_all()
        self.grade.not_run('an earlier step failed')
        self.say('done')
        return self.grade

    step = None                         # the step of the run under way

    def note_unfinished(self):
        """The run was stopped: which step did not finish, in the notes and, when it is an item
        of the rubric, in its evidence."""
        if self.step is None:
            return
        if self.step in rubric.ITEM_NAMES and self.grade.item(self.step) is None:
            self.grade.set(self.step, False, 'not finished: %s while this step ran' % STOPPED)
        self.grade.notes.append('the step %s of the rubric run did not finish: %s while it ran'
                                % (self.step, STOPPED))

    def say(self, text):
        print('[%6.1f s] %s' % (time.monotonic() - self.started, text), flush=True)

    def log_label(self, path):
        """A log's name in the report folder: logs/world_launch.log, logs/world_2/..."""
        return os.path.relpath(path, self.spec.out_dir)

    def excerpt(self, path):
        return launch_excerpt(path, self.spec.out_dir)

    def world_up(self):
        return self.robot is not None and self.ball is not None

    def await_build(self):
        line = sys.stdin.readline()
        message = json.loads(line) if line.strip() else {}
        if 'overlay_env' not in message:
            raise NotBuilt()
        self.use_overlay_env(message['overlay_env'])
        self.launches_as(message.get('chaser_launches_world', False))

    def start_master(self):
        """roscore, in a sandbox of its own when the submission's nodes run in one (core.py),
        its output kept like a launch's; then this process's node, and the watch."""
        cmd = ['roscore', '-p', str(self.spec.master_port)]
        if self.spec.isolate and self.confinement is not None:
            self.core_box = Core(os.path.join(self.spec.grader_dir or self.logs, 'core_%d' % os.getpid()),
                                 self.log_limit)
            cmd, self.core.env = self.core_box.command(self.spec.master_port, self.env,
                                                       environment_paths(self.env))
        log = CappedLog(self.core_log, self.log_limit, mode='wb')
        try:
            self.core.start(cmd, log)
        finally:
            log.started()
        self.open_logs.setdefault(id(self.core), []).append(log)
        deadline = time.monotonic() + 60.0
        while not self.master.is_online():
            if time.monotonic() > deadline or not self.core.alive():
                raise RuntimeError('the ROS master did not start; see %s' % self.log_label(self.core_log))
            time.sleep(POLL_S)
        rospy.core.add_preshutdown_hook(self.on_probe_shutdown)
        rospy.init_node('grade_probe', disable_signals=True)
        threading.Thread(target=self.watch, daemon=True).start()
        self.clock = SimClock()
        self.frames = FrameWatch(self.clock)
        # Until the served type turns out not to be the course's (start_chaser).
        self.counter = CallCounter(self.clock)
        self.moves = ModelMoves()
        self.cmd_sub = rospy.Subscriber('/cmd_vel', Twist, self.on_cmd, queue_size=100)

    def sender(self, topic, port):
        """The node that publishes topic from TCPROS port (a node's topics share its port)."""
        transport = xmlrpc.client.Transport()
        make_connection = transport.make_connection

        def bounded(host):
            connection = make_connection(host)
            connection.timeout = NODE_ANSWER_S
            return connection
        transport.make_connection = bounded
        master = rosgraph.Master(self.master.caller_id)
        try:
            publishers, _subscribers, _services = master.getSystemState()
        except Exception:  # noqa: BLE001 - a master that does not answer names nobody
            return None
        for node in dict(publishers).get(topic, []):
            try:
                node_api = xmlrpc.client.ServerProxy(master.lookupNode(node), transport=transport)
                _code, _text, protocol = node_api.requestTopic(master.caller_id, topic, [['TCPROS']])
                if protocol[2] == port:
                    return node
            except Exception:  # noqa: BLE001 - a node that does not answer is not the one
                continue
        return None

    def on_probe_shutdown(self, reason):
        self.end_run('the grader\'s node %s was shut down (%s)' % (rospy.get_name(), reason))

    def watch(self):
        """End the run when the master ends or this node is shut down: whatever the run waits
        for then (sim time, a service, a message) would never come."""
        while not self.finished:
            trouble = self.core_trouble()
            if trouble:
                self.end_run(trouble)
                return
            if rospy.core.is_shutdown():
                self.end_run('the grader\'s node %s was shut down' % rospy.get_name())
                return
            time.sleep(WATCH_EVERY_S)

    def core_trouble(self):
        """Why the master and rosout can no longer serve the run, as the report says it; ''
        while they can."""
        proc = self.core.procs[-1] if self.core.procs else None
        status = proc.poll() if proc is not None else None
        killed = self.core_box.hit().oom_kills if self.core_box is not None else 0
        if status is None and not killed:
            return ''
        text = 'the ROS master and rosout (roscore) ended during the run'
        if killed:
            text = ('the kernel killed %d process%s of the ROS master and rosout (roscore) at '
                    'their memory limit of %s: what the submission\'s nodes gave them to hold '
                    '(parameters, registrations, messages) went past it'
                    % (killed, '' if killed == 1 else 'es', size_text(self.core_box.limits.memory)))
        if status is not None:
            text += ' (roscore\'s exit status %d)' % status
        return text + '; see %s' % self.log_label(self.core_log)

    def end_run(self, why):
        """Stop the run's steps (SIGINT to this process, raised in the main thread), once."""
        with self.watch_lock:
            if self.finished or self.ended_by is not None:
                return
            self.ended_by = why
            self.interrupt_pending = True
        self.say('ending: %s' % why)
        os.kill(os.getpid(), signal.SIGINT)

    def on_sigint(self, _signum, _frame):
        """The watch's SIGINT ends the steps, unless they have ended already; any other (the
        grader's stop) ends the session."""
        if self.interrupt_pending:
            self.interrupt_pending = False
            if self.finished:
                return
        raise KeyboardInterrupt()

    interrupt_pending = False

    def on_cmd(self, msg):
        self.cmd.append((self.clock.now(), msg.linear.x, msg.angular.z))

    def on_model_states(self, msg):
        self.models = msg
        if self.tracking is not None and self.robot in msg.name:
            robot = msg.pose[msg.name.index(self.robot)]
            # Once taken away (stops_without_ball), the ball is nowhere: no row reaches it.
            ball = (msg.pose[msg.name.index(self.ball)].position if self.ball in msg.name
                    else Point(math.nan, math.nan, math.nan))
            turn = robot.orientation
            yaw = math.atan2(2.0 * (turn.w * turn.z + turn.x * turn.y),
                             1.0 - 2.0 * (turn.y ** 2 + turn.z ** 2))
            self.tracking.append((self.clock.now(), robot.position.x, robot.position.y, yaw,
                                  ball.x, ball.y))

    tracking = None

    def model_pose(self, name):
        msg = self.models
        if msg is None or name not in msg.name:
            return None
        return rosmsg.pose_from_msg(msg.pose[msg.name.index(name)])

    # -- world_launches ---------------------------------------------------------------
    def check_world(self):
        started = time.monotonic()
        robot_dir = os.path.join(self.spec.overlay_root, 'src', self.spec.robot_package)
        self.dropped_nodes = self.prepare_launch_files(robot_dir).dropped
        if self.spec.chaser_launches_world:
            # It starts the world itself: launched alone, as the submission's README runs it.
            self.bring_up_simulator(self.spec.chaser_package, 'ball_chaser.launch')
            self.nodes_before = self.node_names()
            self.start_chaser_launch()
        else:
            # Unchanged: a student's world.launch knows no lockstep argument (enable_lockstep).
            self.bring_up_simulator(self.spec.robot_package, 'world.launch')
            self.start_submission_launch(self.world, self.spec.robot_package, 'world.launch',
                                         self.world_log)
        self.wait_for_world(started)

    def wait_for_world(self, started):
        """world_launches, once its launch has started: the simulator, the robot, the ball."""
        from chase_tools.report import load_world_map
        from flatsim.loading.sdf_world import load_world
        # A bounded queue that holds every state of one read (STATES_QUEUE).
        rospy.Subscriber(chase_graph.MODEL_STATES_TOPIC, chase_graph.model_states_type(),
                         self.on_model_states, queue_size=STATES_QUEUE)
        deadline = started + self.spec.world_timeout
        came = wait_until(lambda: self.models is not None, [self.world], deadline - time.monotonic(),
                          poll_s=POLL_S)
        if not came:
            launch = 'ball_chaser.launch' if self.spec.chaser_launches_world else 'world.launch'
            if self.world.simulator_died:
                why = 'the simulator ended'
            elif not self.world.alive():
                why = '%s ended' % launch
            else:
                why = 'nothing came up within %g s' % self.spec.world_timeout
            if not self.impersonated_world():
                self.grade.set('world_launches', False,
                               'the simulator did not come up: %s; see %s'
                               % (why, self.log_label(self.world_log)),
                               self.excerpt(self.world_log))
            return False
        # The grader's own simulator runs the world it copied (bring_up_simulator).
        notes, world_file = list(self.world_notes), self.world_file
        self.world_map = load_world_map(world_file, notes, self.model_paths)
        world_names = set()
        if world_file:
            try:
                world_names = {model.name for model in load_world(world_file, self.model_paths).models}
            except (FlatsimError, OSError) as error:
                notes.append(str(error))
        self.world_file = world_file
        urdf_name = self.urdf_robot_name()
        while time.monotonic() < deadline and self.world.alive():
            names = set(self.models.name)
            spawned = sorted(names - world_names) or ([urdf_name] if urdf_name in names else [])
            if spawned:
                self.robot = spawned[0]
                break
            time.sleep(POLL_S)
        balls = [name for name in self.world_map.balls if self.models and name in self.models.name]
        self.ball = balls[0] if balls else None
        elapsed = time.monotonic() - started
        problems = []
        if self.robot is None:
            problems.append('no robot was spawned (models: %s)' % ', '.join(self.models.name))
        if self.ball is None:
            problems.append('the world %s has no white ball (a sphere whose colours are all 1)'
                            % os.path.basename(world_file or '(none)'))
        dropped = self.dropped_nodes
        if problems:
            if not self.impersonated_world():
                self.grade.set('world_launches', False, '; '.join(problems + notes),
                               self.excerpt(self.world_log))
            return False
        x, y, radius = self.world_map.balls[self.ball]
        evidence = ('the simulator came up in %.1f s with %s; robot `%s` spawned; white ball `%s` '
                    '(r %.2f m)' % (elapsed, os.path.basename(world_file), self.robot, self.ball, radius))
        if dropped:
            evidence += '; left out (no display): %s' % ', '.join(dropped)
        if self.spec.chaser_launches_world:
            evidence += '; started by ball_chaser.launch, which includes world.launch'
        self.grade.set('world_launches', True, evidence)
        self.spawn_pose = self.model_pose(self.robot)
        self.ball_radius = radius
        self.read_robot_geometry()
        return True

    def impersonated_world(self):
        """True, and world_launches not judged, when a node of the submission took the
        simulator's place while the world came up (the grader's simulator is shut down when
        another node registers under its name)."""
        tampering = self.guard.tampering()
        if tampering:
            self.grade.set('world_launches', False, tampered(tampering), self.excerpt(self.world_log))
        return bool(tampering)

    def has_param(self, name):
        try:
            return self.master.hasParam(name)
        except Exception:  # noqa: BLE001 - a master that does not answer has no such parameter
            return False

    def typed_param(self, name, kinds, what, default, notes):
        """The parameter's value if it is one of kinds, else default. A launch file's <param> is
        typed by how its value reads (value="3" is an int, "true" a bool, a <rosparam> a
        dictionary), so a parameter the grader reads may hold anything: a note then says what."""
        if not self.has_param(name):
            return default
        try:
            value = self.master.getParam(name)
        except rosgraph.masterapi.Error:
            return default
        if isinstance(value, kinds) and not isinstance(value, bool):
            return value
        note = 'the parameter %s holds %s (%s), not %s; it was not used' % (
            name, _short(repr(value), 60), type(value).__name__, what)
        if note not in notes:
            notes.append(note)
        return default

    def urdf_robot_name(self):
        import xml.etree.ElementTree as ET
        text = self.typed_param('/robot_description', str, 'URDF', None, self.grade.notes)
        if text is None:
            return None
        try:
            return ET.fromstring(text).get('name')
        except ET.ParseError:
            return None

    def robot_description(self):
        """(parameter, URDF) of the spawned robot: robot_description, as the course spawns it,
        else the one parameter whose URDF names the spawned model; (None, None) if none does."""
        import xml.etree.ElementTree as ET
        names = ['/robot_description'] + sorted(set(self.master.getParamNames()) - {'/robot_description'})
        found = []
        for name in names:
            if name != '/robot_description' and not name.endswith('robot_description'):
                continue
            if not self.has_param(name):
                continue
            text = self.master.getParam(name)
            if not isinstance(text, str) or '<robot' not in text:
                continue
            try:
                robot_name = ET.fromstring(text).get('name')
            except ET.ParseError:
                continue
            found.append((name, text))
            if name == '/robot_description' or robot_name == self.robot:
                return name, text
        return found[0] if len(found) == 1 else (None, None)

    def read_robot_geometry(self):
        """The spawned robot's outline and camera, read here (trusted) from its URDF with
        flatsim's own loader: xacro has already run, the parameter holds URDF. Also whether
        the design would stand in Gazebo, which flatsim, keeping robots upright, cannot show:
        the rubric's "robot design is stable", advice rather than an item."""
        from flatsim.loading.urdf_robot import load_robot
        self.grade.reach = self.spec.reach
        self.geometry = None
        try:
            name, urdf = self.robot_description()
            if urdf is not None:
                spec = load_robot(urdf, source=name)
                if spec.cameras:
                    largest = max(spec.cameras, key=lambda camera: camera.width * camera.height)
                    self.messages.allow_frames(largest.width, largest.height)
                self.geometry = placement.RobotGeometry.from_spec(spec, CAMERA_TOPIC)
                self.grade.advisories.append(stability_advisory(spec))
        except (FlatsimError, rosgraph.masterapi.Error, OSError) as error:
            self.grade.notes.append('the robot description could not be read: %s' % error)

    # -- sensors ------------------------------------------------------------------------
    def check_sensors(self):
        if not self.world_up():
            self.grade.set('sensors', False, 'not run: the world did not launch')
            return
        chase_graph.SimControl().unpause()
        got = {}

        def keep(name):
            def callback(msg):
                got.setdefault(name, msg)
            return callback
        subs = [rospy.Subscriber(CAMERA_TOPIC, Image, keep('camera'), queue_size=1),
                rospy.Subscriber(SCAN_TOPIC, LaserScan, keep('scan'), queue_size=1)]
        deadline = time.monotonic() + SENSORS_WALL_S
        while len(got) < 2 and time.monotonic() < deadline and self.world.alive():
            time.sleep(POLL_S)
        for sub in subs:
            sub.unregister()
        parts, passed = [], True
        if 'camera' in got:
            image = got['camera']
            parts.append('camera %s %dx%d %s' % (CAMERA_TOPIC, image.width, image.height,
                                                 image.encoding))
        else:
            passed = False
            parts.append('no image on %s (image topics: %s)'
                         % (CAMERA_TOPIC, ', '.join(self.topics_of('sensor_msgs/Image')) or 'none'))
        if 'scan' in got:
            scan = got['scan']
            parts.append('lidar %s %d beams over %.2f..%.2f rad, %.2f-%.1f m'
                         % (SCAN_TOPIC, len(scan.ranges), scan.angle_min, scan.angle_max,
                            scan.range_min, scan.range_max))
        else:
            passed = False
            parts.append('no scan on %s (laser topics: %s)'
                         % (SCAN_TOPIC, ', '.join(self.topics_of('sensor_msgs/LaserScan')) or 'none'))
        self.grade.set('sensors', passed, '; '.join(parts))

    def topics_of(self, msg_type):
        try:
            return sorted(name for name, kind in self.master.getPublishedTopics('') if kind == msg_type)
        except Exception:  # noqa: BLE001 - only for the evidence
            return []

    # -- ball_chaser ------------------------------------------------------------------
    def node_names(self):
        publishers, subscribers, services = self.master.getSystemState()
        return {node for _topic, nodes in publishers + subscribers + services for node in nodes}

    def start_chaser(self):
        # A simulator that is gone (shut down when another node took its name) holds nothing.
        if self.models is not None and self.alive():
            chase_graph.SimControl().pause()
        if not self.spec.chaser_launches_world:
            self.nodes_before = self.node_names()
            self.start_chaser_launch()
        self.wait_for_chaser()
        keep = []
        if self.stand_in_taken():
            # The guess of which node is drive_bot was wrong: it serves the stand-in's name.
            server = self.service_provider(submission.PROXY_SERVICE).lstrip('/').split('/')[-1]
            keep.append(server)
            self.grade.notes.append('%s serves %s but was taken for a client; ball_chaser.launch '
                                    'was started again with it left alone'
                                    % (server, submission.COURSE_SERVICE))
            self.restart_chaser(keep)
        served = self.served_md5()
        if served not in (None, self.counter.srv_type._md5sum):
            self.grade.notes.append(
                '%s is served with md5 %s, not the course\'s DriveToTarget (md5 %s): the grader\'s '
                'counting stand-in cannot forward its calls, so ball_chaser.launch was started '
                'again as written; the chase is judged on its own wiring, and process_image\'s '
                'calls are not counted' % (submission.COURSE_SERVICE, served,
                                           self.counter.srv_type._md5sum))
            self.counter.close()
            self.counter = None
            self.restart_chaser(keep)
        if self.counter is not None and self.chaser_changes.remapped:
            self.grade.notes.append('calls to %s counted from %s (remapped to the grader\'s '
                                    'counting stand-in, which forwards them)'
                                    % (submission.COURSE_SERVICE, ', '.join(self.chaser_changes.remapped)))

    def start_chaser_launch(self, keep=()):
        """Start ball_chaser.launch, its clients' calls sent to the stand-in if it runs."""
        chaser_dir = os.path.join(self.spec.overlay_root, 'src', self.spec.chaser_package)
        self.chaser_changes = self.prepare_launch_files(chaser_dir, remap=self.counter is not None,
                                                        keep=keep)
        self.launch_chaser()

    def launch_chaser(self):
        """Start ball_chaser.launch as prepared."""
        self.chaser_log_start = os.path.getsize(self.chaser_log) if os.path.exists(self.chaser_log) else 0
        self.start_submission_launch(self.chaser, self.spec.chaser_package, 'ball_chaser.launch',
                                     self.chaser_log)

    def restart_chaser(self, keep):
        self.stop_launch(self.chaser, 'ball_chaser.launch')
        if self.counter is not None:
            self.counter.advertise()
        self.start_chaser_launch(keep)
        # When it includes world.launch, the world stays: the simulator is the grader's, and
        # the robot it spawned is still there (a second spawn of it is refused).
        self.wait_for_chaser()

    def wait_for_chaser(self):
        """Until drive_bot's service answers, or ball_chaser.launch's nodes have all died.

        Answers, not only registered: a drive_bot killed with an earlier launch
        stays registered until the new one takes its name.
        """
        deadline = time.monotonic() + self.spec.chaser_timeout
        while time.monotonic() < deadline and self.chaser.alive():
            if self.served_md5() is not None or self.stand_in_taken():
                return
            started, died = launch_processes(self.chaser_log, self.chaser_log_start)
            if started and started <= died:
                return
            time.sleep(POLL_S)

    def served_md5(self):
        """The md5 of the service at the course's name, or None if nothing answers there."""
        uri = self.service_uri(submission.COURSE_SERVICE)
        if uri is None:
            return None
        try:
            return probe.service_headers(uri, submission.COURSE_SERVICE).get('md5sum')
        except probe.ProbeError:
            return None

    def stand_in_taken(self):
        """True when a node of the submission, not this one, serves the stand-in's name."""
        return self.counter is not None and self.service_provider(submission.PROXY_SERVICE) not in (
            None, rospy.get_name())

    @property
    def chaser_nodes(self):
        """The nodes that came with ball_chaser.launch (and are still registered)."""
        if self.nodes_before is None:
            return []
        # The simulator too, when ball_chaser.launch starts the world.
        return sorted(self.node_names() - self.nodes_before
                      - {rospy.get_name(), '/' + WorldLaunch.SIMULATOR})

    def service_uri(self, name):
        try:
            return self.master.lookupService(name)
        except rosgraph.masterapi.Error:
            return None

    def service_provider(self, name):
        _pubs, _subs, services = self.master.getSystemState()
        for service, nodes in services:
            if service == name and nodes:
                return nodes[0]
        return None

    def chaser_services(self):
        _pubs, _subs, services = self.master.getSystemState()
        found = []
        for service, nodes in services:
            if set(nodes) & set(self.chaser_nodes) and not service.endswith(
                    ('/get_loggers', '/set_logger_level')):
                try:
                    kind = probe.service_headers(self.master.lookupService(service),
                                                 service).get('type', '?')
                except (probe.ProbeError, rosgraph.masterapi.Error):
                    kind = '?'
                found.append('%s (%s)' % (service, kind))
        return found

    # -- drive_bot_service --------------------------------------------------------------
    def check_drive_bot(self):
        uri = self.service_uri(submission.COURSE_SERVICE)
        if uri is None:
            offered = self.chaser_services()
            self.grade.set('drive_bot_service', False,
                           '%s is not served; the submission\'s nodes serve %s'
                           % (submission.COURSE_SERVICE, ', '.join(offered) or 'nothing'),
                           self.excerpt(self.chaser_log))
            return
        try:
            headers = probe.service_headers(uri, submission.COURSE_SERVICE)
        except probe.ProbeError as error:
            self.grade.set('drive_bot_service', False, 'the service does not answer: %s' % error,
                           self.excerpt(self.chaser_log))
            return
        from ball_chaser.srv import DriveToTarget
        kind, md5 = headers.get('type', '?'), headers.get('md5sum', '?')
        if md5 != DriveToTarget._md5sum:
            self.grade.set('drive_bot_service', False,
                           'the service has type %s (md5 %s), not the course\'s ball_chaser/'
                           'DriveToTarget (float64 linear_x, float64 angular_z -> string '
                           'msg_feedback, md5 %s)' % (kind, md5, DriveToTarget._md5sum))
            return
        self.wait_for_cmd_publishers()
        # Sim time runs, as it always does in Gazebo: a handler may wait on it (ros::Duration::sleep).
        sim = chase_graph.SimControl() if self.models is not None and self.alive() else None
        if sim is not None:
            sim.unpause()
        try:
            self.probe_drive_bot(DriveToTarget)
        finally:
            if sim is not None:
                sim.pause()

    def call_drive_bot(self, srv_type, request, within):
        """drive_bot's answer to request (linear_x, angular_z), within `within` wall seconds in
        all; rospy.ServiceException otherwise."""
        uri = self.service_uri(submission.COURSE_SERVICE)
        if uri is None:
            raise rospy.ServiceException('service [%s] unavailable' % submission.COURSE_SERVICE)
        try:
            return probe.call_service(uri, submission.COURSE_SERVICE, srv_type,
                                      srv_type._request_class(*request), within)
        except probe.ProbeError as error:
            raise rospy.ServiceException(str(error)) from None

    def probe_drive_bot(self, srv_type):
        """Each request must come out on /cmd_vel as asked. Other commands may come meanwhile
        (a node that sends a stop first, or another publisher of /cmd_vel): the one that
        matches counts, if it comes within COMMAND_WAIT_S of the answer."""
        results = []
        for request in (DRIVE_PROBE, (0.0, 0.0)):
            # A node's first message can leave before a subscriber has connected; ask twice.
            for _attempt in range(2):
                seen = len(self.cmd)
                asked = self.clock.now()
                try:
                    answer = self.call_drive_bot(srv_type, request, DRIVE_CALL_S)
                except rospy.ServiceException as error:
                    self.grade.set('drive_bot_service', False, 'calling it with linear_x %g, '
                                   'angular_z %g (sim time running) failed: %s'
                                   % (request[0], request[1], error),
                                   self.excerpt(self.chaser_log))
                    return
                waited = self.clock.now() - asked
                deadline = time.monotonic() + COMMAND_WAIT_S
                match = None
                while match is None and time.monotonic() < deadline:
                    match = trials.matching_command(self.cmd.since(seen), request, FLOAT_TOLERANCE)
                    time.sleep(0.02)
                published = self.cmd.since(seen)
                if match is not None:
                    break
            if not published:
                self.grade.set('drive_bot_service', False,
                               'a call with linear_x %g, angular_z %g answered "%s" but nothing came '
                               'out on /cmd_vel' % (request[0], request[1],
                                                    _short(answer.msg_feedback)))
                return
            if match is None:
                shown = ', '.join('(%g, %g)' % command[1:] for command in published[-3:])
                self.grade.set('drive_bot_service', False,
                               'a call with linear_x %g, angular_z %g put %d command%s on /cmd_vel '
                               'within %g s, none of them as asked (linear.x, angular.z: %s%s)'
                               % (request[0], request[1], len(published),
                                  '' if len(published) == 1 else 's', COMMAND_WAIT_S,
                                  '... ' if len(published) > 3 else '', shown))
                return
            _t, linear, angular = match
            others = len(published) - 1
            results.append('(%g, %g) -> /cmd_vel (%g, %g), answer "%s"%s%s'
                           % (request[0], request[1], linear, angular, _short(answer.msg_feedback),
                              ' after %.2f s of sim time' % waited if waited >= ANSWER_NOTED_S else '',
                              ' (and %d other command%s meanwhile)' % (others, '' if others == 1 else 's')
                              if others > 0 else ''))
        self.grade.set('drive_bot_service', True, '%s is ball_chaser/DriveToTarget (the course\'s '
                       'md5); with sim time running: %s' % (submission.COURSE_SERVICE, '; '.join(results)))

    def wait_for_cmd_publishers(self, wall_timeout=5.0):
        """Until this node's /cmd_vel subscriber is connected to every publisher of /cmd_vel."""
        deadline = time.monotonic() + wall_timeout
        while time.monotonic() < deadline:
            publishers, _subs, _services = self.master.getSystemState()
            count = sum(len(nodes) for topic, nodes in publishers if topic == '/cmd_vel')
            if self.cmd_sub.get_num_connections() >= count:
                return
            time.sleep(0.05)

    # -- lockstep ------------------------------------------------------------------------
    def enable_lockstep(self):
        """Sim time waits for the controller after each frame, and otherwise runs as fast as it
        can: the outcome no longer depends on the machine's speed or load."""
        if not self.spec.lockstep:
            self.grade.notes.append('chases in real time (--real-time)')
            return
        if not self.world_up():
            return
        publishers, subscribers, _services = self.master.getSystemState()
        chaser_nodes = set(self.chaser_nodes)
        camera = [n for t, nodes in subscribers if t == CAMERA_TOPIC for n in nodes if n in chaser_nodes]
        driver = [n for t, nodes in publishers if t == '/cmd_vel' for n in nodes if n in chaser_nodes]
        if camera and driver:
            # A frame sent before flatsim has connected to the chaser is lost, and a command
            # from a driver it has not yet connected to arrives unannounced.
            wait_until(lambda: chase_graph.lockstep_ready(self.master, CAMERA_TOPIC, chaser=camera[0],
                                                          driver=driver[0]), [], LOCKSTEP_WALL_S, poll_s=0.05)
        sim = chase_graph.SimControl()
        if not sim.set_lockstep(True):
            self.grade.notes.append('the simulator offers no lockstep: chases in real time')
            return
        sim.set_real_time_factor(0.0)
        self.grade.notes.append('chases in lockstep, as fast as the nodes answer')

    # -- trials ---------------------------------------------------------------------------
    def alive(self):
        return self.world.alive()

    def placements(self, count):
        """(placements, notes) for the spawned robot in the world flatsim loaded."""
        from flatsim.loading.sdf_world import load_world
        spawn = (self.spawn_pose.x, self.spawn_pose.y) if self.spawn_pose is not None else (0.0, 0.0)
        plan = placement.plan_placements(load_world(self.world_file, self.model_paths), self.geometry,
                                         count, self.spec.seed, self.ball, keep_out=[self.robot],
                                         spawn=spawn)
        # The view along each trial is judged against the same colliders.
        self.free_space = placement.FreeSpace(load_world(self.world_file, self.model_paths),
                                              keep_out=[self.robot, self.ball])
        return plan

    def start_placement(self, sim, placement):
        """Pause, reset (sim time to 0, every model where it began), place robot and ball with
        the robot at rest, unpause; the sim start time. The same placement then runs the same
        way whatever ran before it."""
        sim.pause()
        # The reset stops the drive too (the last command persists otherwise, as with Gazebo's
        # diff drive). A stop sent on /cmd_vel instead could arrive after the unpause, where
        # lockstep would take it for the controller's answer to the first frame.
        self.clock.begin_run()
        sim.reset()
        self.moves.made()
        sim.place(self.robot, Pose(placement.robot_x, placement.robot_y, 0.0, yaw=placement.robot_yaw))
        self.moves.made()
        sim.place(self.ball, Pose(placement.ball_x, placement.ball_y, self.ball_z))
        if self.counter is not None:
            self.counter.forwarding = True
        sim.unpause()
        return 0.0

    def prepare_trials(self):
        """What every trial needs: the ball's height, the placements, the states' schedule.
        False (the chase item failed) when the trials cannot run."""
        if not self.world_up():
            self.grade.set('chase', False, 'not run: the world did not launch')
            return False
        if self.geometry is None:
            self.grade.set('chase', False, 'not run: no robot_description parameter holds the URDF of '
                           'the spawned robot `%s`, so its outline and camera are unknown' % self.robot)
            return False
        sim = chase_graph.SimControl()
        ball_pose = sim.pose(self.ball)
        self.ball_z = ball_pose[0].position.z if ball_pose else 0.1
        self.read_state_schedule(sim)
        try:
            placements, notes = self.placements(max(self.spec.trials, 1))
        except FlatsimError as error:
            self.grade.set('chase', False, 'no placement could be drawn in this world: %s' % error)
            self.placements_drawn = []
            return False
        self.grade.notes.extend(notes)
        self.placements_drawn = placements
        return True

    def read_state_schedule(self, sim):
        """The physics step and the model states' period, which give each state its sim time."""
        self.time_step = sim.time_step()
        name = '/%s/model_states_rate' % WorldLaunch.SIMULATOR
        rate = self.typed_param(name, (int, float), 'a rate in Hz', DEFAULT_STATES_RATE,
                                self.grade.notes)
        self.states_period = 1.0 / rate if rate > 0 and math.isfinite(rate) else None

    def begin_trials(self):
        """The placements; the extra worlds (spec.worlds) start once this world has chased for
        a while with trials left (worlds.EXTRA_WORLDS_AFTER_S)."""
        from chase_tools.grading import worlds
        self.trials_done = {}
        self.queue = worlds.TrialQueue([])
        if not self.prepare_trials():
            return
        self.queue = worlds.TrialQueue(range(self.spec.trials))
        if self.spec.worlds > 1 and self.spec.trials > 1:
            self.extra_worlds = worlds.ExtraWorlds(self.extra_world_commands(), self.say)
            self.extra_worlds.begin_chase(self.queue, {
                'overlays': dict(self.sandbox.overlays) if self.sandbox is not None else {},
                'count_calls': self.counter is not None, 'ball_z': self.ball_z,
                'placements': [asdict(place) for place in self.placements_drawn]})
            self.extra_worlds.start_after(worlds.EXTRA_WORLDS_AFTER_S)

    def run_trials(self):
        """The chase: this world takes trials one by one, the extra worlds take the others as
        they come up (finish_trials gathers theirs)."""
        self.begin_trials()
        if self.placements_drawn:
            self.run_share(chase_graph.SimControl())

    def run_share(self, sim):
        """Run trials from the queue in this world until none is left."""
        for index in iter(self.queue.take, None):
            place = self.placements_drawn[index]
            trial = rubric.Trial(index, [place.robot_x, place.robot_y, place.robot_yaw],
                                 [place.ball_x, place.ball_y], world=self.spec_world_number())
            self.trials_done[index] = trial
            if not self.alive():
                trial.error = 'world.launch had ended'
                continue
            calls_before = len(self.counter.calls) if self.counter else 0
            self.chase(sim, place, trial)
            if self.counter is not None:
                self.trial_calls += len(self.counter.calls) - calls_before

    def spec_world_number(self):
        return self.spec.extra_world['number'] if self.spec.extra_world else 1

    def extra_world_commands(self):
        """{number: (command, log)} of each extra world's process, its spec written beside this
        one's."""
        overlays = dict(self.sandbox.overlays) if self.sandbox is not None else {}
        commands = {}
        for number in range(2, min(self.spec.worlds, self.spec.trials) + 1):
            folder = 'world_%d' % number
            spec = dict(asdict(self.spec), overlay_env=self.overlay_env, await_build=False,
                        logs_dir=os.path.join(self.logs, folder),
                        grader_dir=os.path.join(self.spec.grader_dir or self.logs, folder),
                        caches_dir=os.path.join(self.spec.caches_dir, folder) if self.spec.caches_dir else '',
                        master_port=(self.spec.master_port + number - 1 if self.spec.isolate
                                     else free_port()),
                        extra_world={'number': number, 'robot': self.robot, 'ball': self.ball,
                                     'overlays': overlays})
            os.makedirs(spec['grader_dir'], mode=0o755, exist_ok=True)
            path = os.path.join(spec['grader_dir'], 'session.json')
            write_new(path, json.dumps(spec))
            os.makedirs(spec['logs_dir'], exist_ok=True)
            commands[number] = ([sys.executable, '-m', 'chase_tools.grading.session', '--world', path],
                                os.path.join(spec['logs_dir'], 'session.log'))
        return commands

    def finish_trials(self):
        """The chase item, once every world's trials are in: trials an extra world gave back
        (its world ended, or it never came up) run here."""
        if not self.placements_drawn and self.grade.item('chase') is not None:
            return
        extra = self.extra_worlds
        if extra is not None:
            extra.finish()
            self.grade.notes.extend(extra.take_notes())
            if self.queue.pending():
                self.run_share(chase_graph.SimControl())
            for index, (trial, calls) in extra.results.items():
                self.trials_done[index] = trial
                self.trial_calls += calls or 0
                self.extra_world_calls += calls or 0
            ran = sorted({trial.world for trial in self.trials_done.values()})
            self.grade.worlds = max(1, len(ran))
            if len(ran) > 1:
                self.grade.notes.append('the trials were shared among %d worlds, each with its own '
                                        'master, simulator and ball_chaser.launch (logs/world_N/)'
                                        % len(ran))
        self.grade.trials = [self.trials_done[index] for index in sorted(self.trials_done)]
        if not self.grade.trials:
            self.grade.set('chase', False, 'not run: no trials were asked for (--trials 0)')
            return
        reached = [t for t in self.grade.trials if t.reached]
        times = sorted(t.time_to_ball for t in reached)
        summary = ('%d of %d placements reached (the robot\'s outline within %.2f m of the ball\'s '
                   'surface, or the ball pushed, within %g s of sim time)'
                   % (len(reached), len(self.grade.trials), self.grade.reach, self.spec.timeout))
        if times:
            summary += '; time to ball median %.1f s, max %.1f s' % (times[len(times) // 2], times[-1])
        summary += '; passes at %.0f%%' % (100 * self.spec.pass_rate)
        errors = ['trial %d: %s' % (t.index, t.error) for t in self.grade.trials if t.error]
        why = ['trial %d: %s' % (t.index, t.reason) for t in self.grade.trials
               if not t.reached and not t.error and t.reason]
        passed = len(reached) >= self.spec.pass_rate * len(self.grade.trials)
        tampering = self.guard.tampering()
        moved_in = [t for t in self.grade.trials if t.error.startswith(MOVED)]
        if tampering or any(t.error.startswith(TAMPERED) for t in self.grade.trials):
            passed = False
            summary = '%s, so no trial counts (%s); %s' % (
                TAMPERED, '; '.join(tampering[:TAMPERING_SHOWN]) or 'see the trials', summary)
        elif moved_in:
            passed = False
            summary = '%s, so no trial counts (%s); %s' % (
                MOVED, '; '.join('trial %d: %s' % (t.index, t.error[len(MOVED) + 2:])
                                 for t in moved_in[:TAMPERING_SHOWN]), summary)
        self.grade.set('chase', passed, summary, ['  ' + line for line in why + errors]
                       + (self.excerpt(self.world_log) if errors else []))

    def chase(self, sim, place, trial):
        """One trial: place, watch until the robot reaches the ball or the time is up, judge."""
        self.tracking = trials.RollingLog(STATES_KEPT)
        commands_before = len(self.cmd)
        calls_before = len(self.counter.calls) if self.counter is not None else 0
        self.frames.subscribe()
        self.moves.begin()
        try:
            start = self.start_placement(sim, place)
        except (FlatsimError, rospy.ServiceException) as error:
            trial.error = 'placing the models failed: %s' % error
            self.tracking = None
            self.frames.stop()
            return
        self.frames.begin()
        robot_start = (place.robot_x, place.robot_y, place.robot_yaw)
        ball_start = (place.ball_x, place.ball_y)
        wall_deadline = time.monotonic() + sim_wall_s(self.spec.timeout)
        placed, checked = False, 0
        while self.alive() and time.monotonic() < wall_deadline:
            new, checked = self.tracking.read(checked)
            if not placed:
                found = trials.placed_row(new, robot_start, ball_start)
                placed = found is not None
                # Until the trial's first state shows, states that came after the reset by the clock.
                new = new[found:] if placed else [row for row in new if row[0] > start]
            if any(self.reached(row, ball_start) for row in new):
                break
            if self.clock.now() - start > self.spec.timeout:
                break
            time.sleep(0.02)
        else:
            trial.error = ('world.launch ended during the trial' if not self.alive()
                           else 'sim time stalled')
        sim.pause()
        self.frames.stop()
        if self.counter is not None:
            self.counter.forwarding = False
        tracked, self.tracking = self.tracking, None
        self.note_dropped(tracked, commands_before, calls_before)
        rows = self.trial_rows(tracked.since(0), robot_start, ball_start, start)
        record = trials.TrialRecord(
            poses=np.array([row for row in rows if row[0] - start <= self.spec.timeout],
                           dtype=float).reshape(-1, 6),
            commands=self.cmd.since(commands_before),
            calls=(self.counter.calls.since(calls_before) if self.counter is not None else None),
            frames=self.frames.frames, white_frames=self.frames.white_frames, ball_start=ball_start)
        record = trials.cut_at_end(self.geometry, record, self.ball_radius, self.grade.reach)
        verdict = trials.judge(self.geometry, self.free_space, record, self.ball_radius, self.grade.reach,
                               self.spec.timeout)
        trial.reached, trial.time_to_ball = verdict.reached, verdict.time_to_ball
        trial.closest, trial.reason, trial.record = verdict.closest, verdict.reason, verdict.facts
        trial.png = self.draw(trial, rows)
        foreign = self.moves.end()
        placed = trials.placed_row(rows, robot_start, ball_start)
        jump = (trials.first_jump(rows[placed:], record.commands,
                                  self.states_period or 1.0 / DEFAULT_STATES_RATE)
                if placed is not None else None)
        tampering = self.guard.tampering()
        if tampering:
            trial.reached, trial.time_to_ball = False, None
            trial.error = tampered(tampering)
        elif foreign or jump is not None:
            trial.reached, trial.time_to_ball = False, None
            trial.error = moved(foreign, jump, self.robot)

    def note_dropped(self, tracked, commands_before, calls_before):
        """A note when a trial brought more than the grader keeps (its oldest were dropped)."""
        dropped = [(tracked.dropped_since(0), 'model states'),
                   (self.cmd.dropped_since(commands_before), 'commands on /cmd_vel')]
        if self.counter is not None:
            dropped.append((self.counter.calls.dropped_since(calls_before), 'calls of process_image'))
        for count, what in dropped:
            note = ('a trial brought more %s than the grader keeps; the oldest were dropped '
                    '(%d in that trial)' % (what, count))
            if count and not any(n.startswith(note.split(' (')[0]) for n in self.grade.notes):
                self.grade.notes.append(note)

    def trial_rows(self, rows, robot_start, ball_start, start):
        """The trial's states from its first on, each at its sim time.

        A state's time is counted from the first (trials.state_times), so it is the same
        in every run; the grader's own /clock, which comes on another connection, can be
        late or early by a few steps. When the count and the clock disagree by more than
        a clock could (a state lost on the way), the clock's times are kept, and a note says so.
        """
        first = trials.placed_row(rows, robot_start, ball_start)
        if first is None or self.states_period is None:
            return [row for row in rows if row[0] > start]
        rows = rows[first:]
        times = trials.state_times(len(rows), self.time_step, self.states_period)
        if any(abs(row[0] - counted) > STATES_CLOCK_TOLERANCE_S for row, counted in zip(rows, times)):
            note = ('the model states did not keep to their schedule; trial times come from the '
                    'grader\'s clock')
            if note not in self.grade.notes:
                self.grade.notes.append(note)
            return [row for row in rows if row[0] > start]
        return [(counted,) + tuple(row[1:]) for row, counted in zip(rows, times)]

    def reached(self, row, ball_start):
        _t, robot_x, robot_y, robot_yaw, ball_x, ball_y = row
        gap = placement.surface_gaps(self.geometry, [(robot_x, robot_y, robot_yaw)], (ball_x, ball_y),
                                     self.ball_radius)[0]
        moved = math.hypot(ball_x - ball_start[0], ball_y - ball_start[1])
        return bool(placement.reached_how(gap, moved, self.grade.reach))

    def draw(self, trial, rows):
        from chase_tools.report import BagSummary, Track as ReportTrack, _write_png, render_trajectory
        if not rows:
            return ''
        summary = BagSummary(path='')
        summary.robot = ReportTrack.of([(t, rx, ry) for t, rx, ry, _yaw, _bx, _by in rows])
        ball = ReportTrack.of([(t, bx, by) for t, _rx, _ry, _yaw, bx, by in rows])
        radius = self.world_map.balls.get(self.ball, (0.0, 0.0, 0.1))[2]
        image, _frame = render_trajectory(summary, self.world_map, ball, radius)
        name = 'trial_%02d.png' % trial.index
        try:
            _write_png(os.path.join(self.spec.out_dir, name), image, [])
        except FlatsimError:
            return ''
        return name

    # -- stops_without_ball ---------------------------------------------------------------
    def check_stop(self):
        if not self.world_up():
            self.grade.set('stops_without_ball', False, 'not run: the world did not launch')
            return
        if not self.placements_drawn or not self.alive():
            self.grade.set('stops_without_ball', False, 'not run: no placement, or the world ended')
            return
        sim = chase_graph.SimControl()
        placement = self.placements_drawn[0]
        self.tracking = trials.RollingLog(STATES_KEPT)
        self.moves.begin()
        start = self.start_placement(sim, placement)
        seen = len(self.cmd)
        # Let the robot set off toward the ball: a non-zero command, up to 5 s of sim time.
        deadline = time.monotonic() + SET_OFF_WALL_S
        while (self.alive() and time.monotonic() < deadline and self.clock.now() - start < 5.0
               and not trials.moving(self.cmd.since(seen), STILL_SPEED)):
            time.sleep(0.02)
        moving = trials.moving(self.cmd.since(seen), STILL_SPEED)
        if not moving:
            sim.pause()
            self.tracking = None
            self.grade.set('stops_without_ball', False,
                           'with the ball %.1f m ahead the robot was never commanded to move in 5 s, '
                           'so stopping cannot be shown' % placement.ball_distance,
                           self.excerpt(self.chaser_log))
            return
        self.clock.wait(0.5, self.alive)
        hidden_at = self.clock.now()
        sim.delete(self.ball)
        self.clock.wait(REACT_S + WATCH_S, self.alive)
        ended_at = self.clock.now()
        sim.pause()
        tracked, self.tracking = self.tracking, None
        if self.counter is not None:
            self.counter.forwarding = False
        poses = [row[:4] for row in tracked.since(0) if row[0] >= hidden_at]
        window = hidden_at + REACT_S
        verdict = trials.judge_stop(self.cmd.since(seen), poses, window, STILL_SPEED,
                                    STILL_DISTANCE_M, STILL_TURN_RAD)
        tampering = self.guard.tampering()
        if tampering:
            self.grade.set('stops_without_ball', False, tampered(tampering))
            return
        foreign = self.moves.end()
        if foreign:
            self.grade.set('stops_without_ball', False, moved(foreign, None, self.robot))
            return
        if verdict.poses < 2:
            self.grade.set('stops_without_ball', False, 'the robot\'s pose could not be read over '
                           'the %g s after the ball was taken away' % (ended_at - window))
            return
        _t, linear, angular = moving[-1]
        text = ('the robot was driving toward the ball (command %.2f m/s, %.2f rad/s); the ball was '
                'taken away %.1f s after the start; after %g s to react, over the next %.1f s the '
                'robot travelled %.2f m and turned %.2f rad along its path'
                % (linear, angular, hidden_at - start, REACT_S, ended_at - window, verdict.path_m,
                   verdict.turned_rad))
        if verdict.moving_commands:
            text += ('; %d motion command%s in effect then, the first (%.2f, %.2f)'
                     % (verdict.moving_commands, '' if verdict.moving_commands == 1 else 's',
                        verdict.first_moving[1], verdict.first_moving[2]))
        else:
            text += '; every command in effect then was a stop'
        if verdict.last_command is not None:
            text += ', the last (%.2f, %.2f)' % verdict.last_command[1:]
        self.grade.set('stops_without_ball', verdict.still, text)

    # -- process_image_calls --------------------------------------------------------------
    def check_process_image(self):
        if self.nodes_before is None:
            return
        chaser_nodes = self.chaser_nodes
        _pubs, subscribers, _services = self.master.getSystemState()
        camera_nodes = sorted({node for topic, nodes in subscribers if topic == CAMERA_TOPIC
                               for node in nodes if node in chaser_nodes})
        if not camera_nodes:
            self.grade.set('process_image_calls', False,
                           'no node of ball_chaser.launch subscribes to %s (its nodes: %s)'
                           % (CAMERA_TOPIC, ', '.join(chaser_nodes) or 'none'),
                           self.excerpt(self.chaser_log))
            return
        if self.counter is None:
            self.grade.set('process_image_calls', False,
                           '%s subscribes to %s, but the submission\'s DriveToTarget is not the '
                           'course\'s, so its calls could not be counted'
                           % (', '.join(camera_nodes), CAMERA_TOPIC))
            return
        calls = self.counter.calls
        # The extra worlds' calls came during their trials.
        total = len(calls) + self.extra_world_calls
        if not total:
            self.grade.set('process_image_calls', False,
                           '%s subscribes to %s but never called %s'
                           % (', '.join(camera_nodes), CAMERA_TOPIC, submission.COURSE_SERVICE),
                           self.excerpt(self.chaser_log))
            return
        kept = calls.since(0)
        first = ', first with linear_x %.2f, angular_z %.2f' % kept[0][1:] if kept else ''
        self.grade.set('process_image_calls', True,
                       '%s subscribes to %s and called %s %d times (%d during the chase trials)%s'
                       % (', '.join(camera_nodes), CAMERA_TOPIC, submission.COURSE_SERVICE,
                          total, self.trial_calls, first))

    nodes_before = None
    placements_drawn = ()
    extra_worlds = None
    trial_calls = 0                    # process_image's calls during the trials, every world's
    extra_world_calls = 0
    spawn_pose = None
    geometry = None


class TrialWorld(Session):
    """An extra world for a share of the chase (grading/worlds.py), in a process of its own.

    Its own master on its own port, the submission's world.launch and
    ball_chaser.launch as the session's own world prepared them (the same
    launch files, the same choice of what is remapped), in the same sandbox,
    then the trials the session hands it, one at a time, each run as the
    session's own world runs one. It speaks JSON lines on its channel and
    reads them on stdin:

      it says {"world_up": true} once its world is up (or {"failed": why});
      it reads {"chase": {"overlays", "count_calls", "ball_z", "placements"}}, starts
        ball_chaser.launch and lockstep, and says {"ready": true} (or {"failed": why});
      for each {"run": index} it reads, it says {"trial": {...}, "calls": n}, or
        {"gave_back": index, "why": ...} when its world has ended;
      at {"stop": true}, at the end of its input or at SIGINT, it stops and says
        {"notes": [...]}.
    """

    def __init__(self, spec, channel, requests=sys.stdin):
        super().__init__(spec)
        self.channel, self.requests = channel, requests
        self.share = spec.extra_world
        self.number = self.share['number']
        if self.sandbox is not None:
            self.sandbox.overlays = dict(self.share['overlays'])
        self.dropped_nodes = []
        self.notes_before = 0

    def tell(self, **message):
        self.channel.write(json.dumps(message) + '\n')
        self.channel.flush()

    def ask(self):
        """The session's next message; {} at the end of the input."""
        line = self.requests.readline()
        return json.loads(line) if line.strip() else {}

    def run(self):
        self.started = time.monotonic()
        try:
            if not self.come_up(self.bring_up_world, 'world_up'):
                return
            chase = self.ask().get('chase')
            if chase is None or not self.come_up(lambda: self.bring_up_chaser(chase), 'ready'):
                return
            self.notes_before = len(self.grade.notes)
            self.serve()
        finally:
            self.say('stopping')
            self.stop_all()
            self.tell(notes=['world %d: %s' % (self.number, note)
                             for note in self.grade.notes[self.notes_before:]])
            self.say('done')

    def come_up(self, step, say):
        """True once step() came up (''), told the session; else the session is told why not."""
        try:
            why = step()
        except Exception as error:  # noqa: BLE001 - the other worlds run the trials then
            import traceback
            traceback.print_exc()
            why = '%s: %s' % (type(error).__name__, error)
        if why:
            self.say('not up: %s' % why)
            self.tell(failed=why)
            return False
        self.say(say)
        self.tell(**{say: True})
        return True

    def bring_up_world(self):
        """'' once the master and the world are up as in the session's world; else why not."""
        self.start_master()
        if self.spec.chaser_launches_world:
            return ''
        started = time.monotonic()
        self.bring_up_simulator(self.spec.robot_package, 'world.launch')
        self.start_submission_launch(self.world, self.spec.robot_package, 'world.launch',
                                     self.world_log)
        return self.check_same_world(started)

    def check_same_world(self, started):
        if not self.wait_for_world(started):
            return 'its world did not come up: %s' % self.grade.item('world_launches').evidence.split('\n')[0]
        if (self.robot, self.ball) != (self.share['robot'], self.share['ball']):
            return ('its world holds robot %s and ball %s, where the session\'s holds %s and %s'
                    % (self.robot, self.ball, self.share['robot'], self.share['ball']))
        if self.geometry is None:
            return 'the robot description could not be read'
        return ''

    def bring_up_chaser(self, chase):
        """'' once ball_chaser.launch runs and the world is in lockstep; else why not."""
        from flatsim.loading.sdf_world import load_world
        if self.sandbox is not None:
            self.sandbox.overlays = dict(chase['overlays'])
        if not chase['count_calls']:
            self.counter.close()
            self.counter = None
        started = time.monotonic()
        sim = chase_graph.SimControl()
        if not self.spec.chaser_launches_world:
            # Held while the chaser comes up, as in the session's world: lockstep must not meet
            # frames that no command answers (their calls are held until a trial begins), or
            # it would learn to wait for the controller no longer than min_wait.
            sim.pause()
        if self.spec.chaser_launches_world:
            self.bring_up_simulator(self.spec.chaser_package, 'ball_chaser.launch')
        self.nodes_before = self.node_names()
        self.launch_chaser()
        if self.spec.chaser_launches_world:
            why = self.check_same_world(started)
            if why:
                return why
            sim.pause()
        self.wait_for_chaser()
        if self.served_md5() is None:
            return '%s was not served' % submission.COURSE_SERVICE
        self.wait_for_cmd_publishers()
        self.warm_up(sim)
        self.enable_lockstep()
        self.ball_z = chase['ball_z']
        self.read_state_schedule(sim)
        self.placements_drawn = [placement.Placement(**place) for place in chase['placements']]
        self.free_space = placement.FreeSpace(load_world(self.world_file, self.model_paths),
                                              keep_out=[self.robot, self.ball])
        return ''

    def warm_up(self, sim, wall_timeout=WARM_UP_S):
        """The chaser as the session's own world has it by its first trial, after its checks:
        drive_bot called, process_image having seen frames and called. A node's first answer is
        slow (its first connections and calls), and lockstep waits at most a second for one: a
        first trial answered late would not come out as it does in another world."""
        from ball_chaser.srv import DriveToTarget
        seen = len(self.cmd)
        sim.unpause()
        try:
            self.call_drive_bot(DriveToTarget, (0.0, 0.0), wall_timeout)
        except rospy.ServiceException:
            pass
        if self.counter is not None:
            called = lambda: bool(self.counter.calls)                       # noqa: E731
        else:
            called = lambda: len(self.cmd) > seen + 1                        # noqa: E731
        wait_until(called, [self.world, self.chaser], wall_timeout, poll_s=POLL_S)
        sim.pause()

    def serve(self):
        sim = chase_graph.SimControl()
        for index in iter(lambda: self.ask().get('run'), None):
            if not self.alive():
                self.tell(gave_back=index, why='its world had ended')
                return
            place = self.placements_drawn[index]
            trial = rubric.Trial(index, [place.robot_x, place.robot_y, place.robot_yaw],
                                 [place.ball_x, place.ball_y], world=self.number)
            calls_before = len(self.counter.calls) if self.counter is not None else 0
            self.say('trial %d' % index)
            self.chase(sim, place, trial)
            calls = len(self.counter.calls) - calls_before if self.counter is not None else None
            self.tell(trial=asdict(trial), calls=calls)


def _short(text, limit=80):
    text = ' '.join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + '...'


def heard_path(result_path):
    """The file the session makes as soon as it hears SIGINT: until then the grader keeps the
    submission running, so that no item is judged on nodes the stop is killing."""
    return result_path + '.heard'


def main(argv=None):
    """Run the session; its result goes to RESULT.json (a new file), also when it is stopped
    (SIGINT), with what it found until then. With --world SPEC.json, an extra world for a share
    of the trials (TrialWorld), speaking on stdout."""
    argv = sys.argv[1:] if argv is None else argv
    if argv[0] == '--world':
        with open(argv[1]) as stream:
            spec = SessionSpec(**json.load(stream))
        # stdout is the channel to the session; whatever else writes there goes to the log.
        channel = os.fdopen(os.dup(sys.stdout.fileno()), 'w')
        os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
        try:
            TrialWorld(spec, channel).run()
        except KeyboardInterrupt:
            return 130
        return 0
    with open(argv[0]) as stream:
        spec = SessionSpec(**json.load(stream))
    session = Session(spec)
    status = 0

    def hear_stop(_signum, _frame):
        signal.signal(signal.SIGINT, signal.default_int_handler)
        try:
            os.close(os.open(heard_path(argv[1]), os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        except OSError:
            pass
        raise KeyboardInterrupt
    signal.signal(signal.SIGINT, hear_stop)
    try:
        grade = session.run()
    except KeyboardInterrupt:
        print('interrupted: the master, the world and the nodes are stopped', flush=True)
        grade = session.grade
        session.note_unfinished()
        grade.not_run(STOPPED)
        status = 130
    write_new(argv[1], json.dumps(grade.as_json(), indent=2) + '\n')
    return status


if __name__ == '__main__':
    sys.exit(main())
