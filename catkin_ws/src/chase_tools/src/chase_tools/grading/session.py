"""The rubric run of one built submission, headless, in a network namespace of its own.

grade.py starts this module in a fresh process inside a network namespace that
holds only loopback (sandbox.network_namespace_command), while the build runs.
Here it starts a ROS master (trusted), waits for the built workspace (SessionSpec.
await_build), launches the submission's world.launch and ball_chaser.launch
inside the sandbox, then checks, in order:

  world_launches      the simulator comes up, the robot is spawned, the world has a white ball;
  sensors             a camera image on /camera/rgb/image_raw and a scan on /scan;
  drive_bot_service   with sim time running: /ball_chaser/command_robot has the course's
                      DriveToTarget type, or the course's request with another response
                      (service_type.py: called with the submission's own type), and a
                      request comes out on /cmd_vel as asked;
  chase               N seeded placements (whole ball in the robot's camera view), each
                      with ball_chaser.launch started afresh on it (the world paused), and
                      chased until the robot's outline comes within the reach of the
                      ball's surface or the time runs out; each failed trial says why
                      (grading/trials.py), and a PNG of each; extra worlds take a
                      share of the trials (TrialWorld, grading/worlds.py);
  process_image_calls the node subscribed to the camera called the service during the chase;
  stops_without_ball  on a placement, ball_chaser.launch started afresh, the robot drives
                      toward the ball, the ball is taken away, and the robot's command and
                      motion must come to zero.

process_image's calls are counted without touching its code: its launch file
(in the grader's copy) remaps the absolute name /ball_chaser/command_robot to
/grader/command_robot, where this process serves a stand-in that records each
request and forwards it to drive_bot. roscpp and rospy both apply remappings
to absolute names. The stand-in serves the course's DriveToTarget, or the
submission's own type when only its response differs (read from its .srv as
text, never imported: service_type.py). A drive_bot whose request is not the
course's gets its calls straight from process_image, uncounted, so that the
chase is judged on the submission's own wiring.

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
import os
import signal
import sys
import time
from dataclasses import dataclass

from chase_tools.reach import SURFACE_REACH_M
from chase_tools.grading import rubric
from chase_tools.grading.chase import Chase, SessionTrials
from chase_tools.grading.chaser import Chaser
from chase_tools.grading.checks import Checks
from chase_tools.grading.launches import Launches
from chase_tools.grading.node import GraderNode
from chase_tools.grading.scratch import write_new
from chase_tools.grading.trial_world import TrialWorld
from chase_tools.grading.world_check import WorldCheck


# Why the items not yet run failed when the session was stopped; the grader says by what.
STOPPED = 'the grade was stopped'


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
    reach: float = SURFACE_REACH_M  # m from the robot's outline to the ball's surface
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
    # The uids the grader gave the session (session_user.SessionUser.uids_json): its own, and
    # each world's roscore's and simulator's; None when the grader does not run as root.
    uids: dict = None


class NotBuilt(Exception):
    """The session was started before the build, which did not end in a workspace to run."""


class Session(WorldCheck, Chaser, Checks, Chase, SessionTrials, Launches, GraderNode):
    """The session's own world: every part of a run, in the rubric's order (run)."""

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

    def await_build(self):
        line = sys.stdin.readline()
        message = json.loads(line) if line.strip() else {}
        if 'overlay_env' not in message:
            raise NotBuilt()
        self.use_overlay_env(message['overlay_env'])
        self.launches_as(message.get('chaser_launches_world', False))


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
