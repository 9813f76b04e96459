"""One world's run as the grader holds it: its master (roscore) and its own node, the process
groups of the submission's launches, what the node hears, and how it all stops.

The parts of a run (launches.Launches, world_check.WorldCheck, chaser.Chaser, checks.Checks,
chase.Chase, chase.SessionTrials) are mixins over the state GraderNode sets up: the session's
own world (session.Session) takes every part, an extra world (trial_world.TrialWorld) only the
ones its trials need.
"""
import math
import os
import signal
import threading
import time
import xmlrpc.client
from dataclasses import dataclass, field

import rosgraph
import rospy
from geometry_msgs.msg import Point, Twist

from chase_tools.grading import rubric, trials
from chase_tools.grading.bounds import (COMMANDS_KEPT, NODE_ANSWER_S, POLL_S, QUICK_START, SIMULATOR_REFUSALS,
                                        STOP_GRACE_S, WATCH_EVERY_S)
from chase_tools.grading.core import Core, logging_config
from chase_tools.grading.guard import ModelMoves, SimulatorGuard
from chase_tools.grading.launches import WorldLaunch, launch_excerpt
from chase_tools.grading.limits import Limits, size_text
from chase_tools.grading.listeners import CallCounter, FrameWatch, SimClock
from chase_tools.grading.logcap import CappedLog
from chase_tools.grading.message_limit import RECORD_LIMIT, MessageLimit, simulator_notes
from chase_tools.grading.sandbox import Confinement, allowed_environment, environment_paths
from chase_tools.grading.sandbox_processes import end_sandbox
from chase_tools.grading.scratch import read_beneath
from chase_tools.procs import ProcessGroup
from flatsim.ros import messages as rosmsg


@dataclass
class WorldFindings:
    """What a world's run finds as it goes, each set by the step that finds it: None or empty
    until then, and so for the steps after it when it found nothing."""
    # The world (Launches.bring_up_simulator, WorldCheck.wait_for_world).
    world_file: str = None             # the grader's copy of the world the simulator runs
    model_paths: list = field(default_factory=list)   # where the includes of that copy lie
    world_notes: list = field(default_factory=list)   # what could not be read of it
    world_map: object = None           # report.load_world_map of it: walls, boxes, balls
    robot: str = None                  # the spawned robot's model
    ball: str = None                   # the white ball's model
    ball_radius: float = None
    spawn_pose: object = None
    geometry: object = None            # placement.RobotGeometry from the robot's URDF
    dropped_nodes: list = field(default_factory=list)  # display nodes left out of the launch
    # ball_chaser.launch (Chaser).
    nodes_before: set = None           # the nodes registered before it started
    chaser_changes: object = None      # headless_launch.prepare_launch_files' changes to it
    # (md5, service_type.ServiceDefinition or the ServiceTypeError why not) of the type served
    # at the course's name, when it is not the course's (Chaser.own_service).
    own_service: tuple = None
    # The trials (Chase, SessionTrials).
    ball_z: float = None
    placements_drawn: list = ()
    free_space: object = None          # placement.FreeSpace that each trial's view is judged in
    time_step: float = None            # the physics step and the model states' period
    states_period: float = None
    trial_calls: int = 0               # process_image's calls during the trials, every world's
    extra_world_calls: int = 0


class GraderNode:
    """What every world's run holds: the spec, the grade, the environments, the master and the
    grader's node, the launches' process groups, and what the node hears of the run."""

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
        self.log_cuts = {}              # a launch log's path -> (bytes cut, written, starts)
        self.asked_while_running = set()   # id(group) of launches asked to stop while running
        self.prepared = 0               # launch files prepared so far, each set in a folder of its own
        self.world_copies = 0           # the same for the world's copies
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
        self.master = rosgraph.Master('/grade_probe')
        self.world_log = os.path.join(self.logs, 'world_launch.log')
        self.chaser_log = os.path.join(self.logs, 'ball_chaser_launch.log')
        self.launches_as(spec.chaser_launches_world)
        self.models = None
        self.cmd = trials.RollingLog(COMMANDS_KEPT)    # (sim time, linear.x, angular.z) on /cmd_vel
        self.guard = SimulatorGuard(self.master)
        self.found = WorldFindings()

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
        self.grade.notes.extend(self.core_box.master_notes())
        self.core_box.end()
        for relative, cap in self.core_box.copy_logs(os.path.join(self.logs, 'ros', 'log')):
            full = self.core_box.limits.file_size
            self.grade.notes.append('%s: %s cut of %s written (the first and last %s kept)%s' % (
                self.log_label(os.path.join(self.logs, 'ros', 'log', relative)), size_text(cap.cut),
                size_text(cap.total), size_text(cap.keep // 2),
                '; roscore\'s file size limit of %s ended it there' % size_text(full)
                if cap.total >= full else ''))

    def given_uid(self, kind):
        """The uid the grader gave this world's roscore ('core') or simulator, or None: this
        process then picks one (as root) or uses its own."""
        uids = (self.spec.uids or {}).get(kind)
        number = self.spec.extra_world['number'] if self.spec.extra_world else 1
        return uids[number - 1] if uids and number <= len(uids) else None

    def say(self, text):
        print('[%6.1f s] %s' % (time.monotonic() - self.started, text), flush=True)

    def log_label(self, path):
        """A log's name in the report folder: logs/world_launch.log, logs/world_2/..."""
        return os.path.relpath(path, self.spec.out_dir)

    def excerpt(self, path):
        return launch_excerpt(path, self.spec.out_dir)

    def world_up(self):
        return self.found.robot is not None and self.found.ball is not None

    def start_master(self):
        """roscore, in a sandbox of its own when the submission's nodes run in one (core.py),
        its output kept like a launch's; then this process's node, and the watch."""
        cmd = ['roscore', '-p', str(self.spec.master_port)]
        if self.spec.isolate and self.confinement is not None:
            self.core_box = Core(os.path.join(self.spec.grader_dir or self.logs, 'core_%d' % os.getpid()),
                                 self.log_limit, uid=self.given_uid('core'))
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
        if self.tracking is not None and self.found.robot in msg.name:
            robot = msg.pose[msg.name.index(self.found.robot)]
            # Once taken away (stops_without_ball), the ball is nowhere: no row reaches it.
            ball = (msg.pose[msg.name.index(self.found.ball)].position if self.found.ball in msg.name
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

    def alive(self):
        return self.world.alive()

    extra_worlds = None
