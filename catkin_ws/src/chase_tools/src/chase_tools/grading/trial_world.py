"""An extra world for a share of the chase, in a process of its own (grading/worlds.py)."""
import json
import sys
import time
from dataclasses import asdict

import rospy

from chase_tools import chase_graph, placement
from chase_tools.grading import course_service, rubric, service_type, submission
from chase_tools.grading.bounds import POLL_S, WARM_UP_S
from chase_tools.grading.chase import Chase
from chase_tools.grading.chaser import Chaser
from chase_tools.grading.launches import Launches
from chase_tools.grading.node import GraderNode
from chase_tools.grading.world_check import WorldCheck
from chase_tools.procs import wait_until


class TrialWorld(WorldCheck, Chaser, Chase, Launches, GraderNode):
    """An extra world for a share of the chase (grading/worlds.py), in a process of its own.

    Its own master on its own port, the submission's world.launch and
    ball_chaser.launch as the session's own world prepared them (the same
    launch files, the same choice of what is remapped), in the same sandbox,
    then the trials the session hands it, one at a time, each run as the
    session's own world runs one. It speaks JSON lines on its channel and
    reads them on stdin:

      it says {"world_up": true} once its world is up (or {"failed": why});
      it reads {"chase": {"overlays", "count_calls", "own_service", "ball_z", "placements"}}, starts
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
        if (self.found.robot, self.found.ball) != (self.share['robot'], self.share['ball']):
            return ('its world holds robot %s and ball %s, where the session\'s holds %s and %s'
                    % (self.found.robot, self.found.ball, self.share['robot'], self.share['ball']))
        if self.found.geometry is None:
            return 'the robot description could not be read'
        return ''

    def bring_up_chaser(self, chase):
        """'' once ball_chaser.launch runs and the world is in lockstep; else why not."""
        from flatsim.loading.sdf_world import load_world
        if self.sandbox is not None:
            self.sandbox.overlays = dict(chase['overlays'])
        self.count_as_the_session(chase)
        started = time.monotonic()
        sim = chase_graph.SimControl()
        if not self.spec.chaser_launches_world:
            # Held while the chaser comes up, as in the session's world: lockstep must not meet
            # frames that no command answers (their calls are held until a trial begins), or
            # it would learn to wait for the controller no longer than min_wait.
            sim.pause()
        if self.spec.chaser_launches_world:
            self.bring_up_simulator(self.spec.chaser_package, 'ball_chaser.launch')
        self.found.nodes_before = self.node_names()
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
        self.found.ball_z = chase['ball_z']
        self.read_state_schedule(sim)
        self.found.placements_drawn = [placement.Placement(**place) for place in chase['placements']]
        found = self.found
        found.free_space = placement.FreeSpace(load_world(found.world_file, found.model_paths),
                                               keep_out=[found.robot, found.ball])
        return ''

    def count_as_the_session(self, chase):
        """The counting stand-in as the session's own world has it: gone, or serving the
        course's type or the submission's own (Chase.own_service_share)."""
        if not chase['count_calls']:
            self.counter.close()
            self.counter = None
        elif chase.get('own_service'):
            own = chase['own_service']
            self.counter.serve_as(service_type.service_class(
                service_type.parse_srv(own['text'], own['type'])))

    def warm_up(self, sim, wall_timeout=WARM_UP_S):
        """The chaser as the session's own world has it by its first trial, after its checks:
        drive_bot called, process_image having seen frames and called. A node's first answer is
        slow (its first connections and calls), and lockstep waits at most a second for one: a
        first trial answered late would not come out as it does in another world."""
        seen = len(self.cmd)
        sim.unpause()
        try:
            self.call_drive_bot(self.counter.srv_type if self.counter is not None
                                else course_service.course_drive_to_target(), (0.0, 0.0), wall_timeout)
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
            place = self.found.placements_drawn[index]
            trial = rubric.Trial(index, [place.robot_x, place.robot_y, place.robot_yaw],
                                 [place.ball_x, place.ball_y], world=self.number)
            calls_before = len(self.counter.calls) if self.counter is not None else 0
            self.say('trial %d' % index)
            self.chase(sim, place, trial)
            calls = len(self.counter.calls) - calls_before if self.counter is not None else None
            self.tell(trial=asdict(trial), calls=calls)
