"""The chase: one trial in any world (Chase), and the session's trials shared among its worlds
and judged together (SessionTrials)."""
import json
import math
import os
import sys
import time
from dataclasses import asdict

import numpy as np
import rospy

from chase_tools import chase_graph, placement, reach
from chase_tools.grading import rubric, service_type, trials
from chase_tools.grading.bounds import (DEFAULT_STATES_RATE, STATES_CLOCK_TOLERANCE_S, STATES_KEPT,
                                        sim_wall_s)
from chase_tools.grading.guard import MOVED, TAMPERED, TAMPERING_SHOWN, moved, tampered
from chase_tools.grading.launches import WorldLaunch
from chase_tools.grading.scratch import write_new
from chase_tools.grading.worlds import free_port
from flatsim.errors import FlatsimError
from flatsim.pose import Pose


class Chase:
    """One trial, placed, chased and judged, in whichever world runs it; a part of a world's run."""

    def start_placement(self, sim, placement):
        """Pause, reset (sim time to 0, every model where it began), place robot and ball with
        the robot at rest, start ball_chaser.launch afresh (Chaser.start_chaser_afresh), unpause;
        the sim start time. The same placement then runs the same way whatever ran before it."""
        sim.pause()
        # The reset stops the drive too (the last command persists otherwise, as with Gazebo's
        # diff drive). A stop sent on /cmd_vel instead could arrive after the unpause, where
        # lockstep would take it for the controller's answer to the first frame.
        self.clock.begin_run()
        sim.reset()
        self.moves.made()
        sim.place(self.found.robot, Pose(placement.robot_x, placement.robot_y, 0.0, yaw=placement.robot_yaw))
        self.moves.made()
        sim.place(self.found.ball, Pose(placement.ball_x, placement.ball_y, self.found.ball_z))
        # The nodes start afresh on the placement, which the paused world holds meanwhile.
        self.start_chaser_afresh()
        if self.counter is not None:
            self.counter.forwarding = True
        sim.unpause()
        return 0.0

    def read_state_schedule(self, sim):
        """The physics step and the model states' period, which give each state its sim time."""
        self.found.time_step = sim.time_step()
        name = '/%s/model_states_rate' % WorldLaunch.SIMULATOR
        rate = self.typed_param(name, (int, float), 'a rate in Hz', DEFAULT_STATES_RATE,
                                self.grade.notes)
        self.found.states_period = 1.0 / rate if rate > 0 and math.isfinite(rate) else None

    def spec_world_number(self):
        return self.spec.extra_world['number'] if self.spec.extra_world else 1

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
        record = trials.cut_at_end(self.found.geometry, record, self.found.ball_radius, self.grade.reach)
        found = self.found
        verdict = trials.judge(found.geometry, found.free_space, record, found.ball_radius,
                               self.grade.reach, self.spec.timeout)
        trial.reached, trial.time_to_ball = verdict.reached, verdict.time_to_ball
        trial.closest, trial.reason, trial.record = verdict.closest, verdict.reason, verdict.facts
        foreign = self.moves.end()
        placed = trials.placed_row(rows, robot_start, ball_start)
        jump = (trials.first_jump(rows[placed:], record.commands,
                                  self.found.states_period or 1.0 / DEFAULT_STATES_RATE)
                if placed is not None else None)
        tampering = self.guard.tampering()
        if tampering:
            trial.reached, trial.time_to_ball = False, None
            trial.error = tampered(tampering)
        elif foreign or jump is not None:
            trial.reached, trial.time_to_ball = False, None
            trial.error = moved(foreign, jump, self.found.robot)
        trial.png = self.draw(trial, rows)

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
        if first is None or self.found.states_period is None:
            return [row for row in rows if row[0] > start]
        rows = rows[first:]
        times = trials.state_times(len(rows), self.found.time_step, self.found.states_period)
        if any(abs(row[0] - counted) > STATES_CLOCK_TOLERANCE_S for row, counted in zip(rows, times)):
            note = ('the model states did not keep to their schedule; trial times come from the '
                    'grader\'s clock')
            if note not in self.grade.notes:
                self.grade.notes.append(note)
            return [row for row in rows if row[0] > start]
        return [(counted,) + tuple(row[1:]) for row, counted in zip(rows, times)]

    def reached(self, row, ball_start):
        _t, robot_x, robot_y, robot_yaw, ball_x, ball_y = row
        gap = reach.surface_gaps(self.found.geometry, [(robot_x, robot_y, robot_yaw)], (ball_x, ball_y),
                                     self.found.ball_radius)[0]
        moved = math.hypot(ball_x - ball_start[0], ball_y - ball_start[1])
        return bool(reach.surface_reached_how(gap, moved, self.grade.reach))

    def draw_world(self, sim):
        """world.png: the world from above as flatsim simulates it, the robot where it stands;
        '' if it could not be written."""
        from chase_tools.drawing import render_world, write_png
        from flatsim.ros.messages import pose_from_msg
        state = sim.pose(self.found.robot)
        robot_pose = None
        if state is not None:
            pose = pose_from_msg(state[0])
            robot_pose = (pose.x, pose.y, pose.yaw)
        footprint = self.found.geometry.footprint if self.found.geometry is not None else ()
        image, _frame = render_world(self.found.world_map, robot_pose, footprint,
                                     'no placement could be drawn')
        try:
            write_png(os.path.join(self.spec.out_dir, rubric.WORLD_PICTURE), image)
        except FlatsimError:
            return ''
        return rubric.WORLD_PICTURE

    def draw(self, trial, rows):
        """trial_NN.png: the trial from above, zoomed on it (drawing.render_trial)."""
        from chase_tools.drawing import TrialPicture, render_trial, write_png
        if not rows:
            return ''
        rows = np.asarray(rows, dtype=float).reshape(-1, 6)
        geometry, ball_radius = self.found.geometry, self.found.ball_radius or 0.1
        camera = None
        if geometry is not None:
            camera = (*geometry.camera.world(*rows[0, 1:4]), geometry.camera.hfov)
        if trial.error:
            outcome = ': '.join(trial.error.split(': ')[:2])
        elif trial.reached:
            outcome = 'reached' + ('' if trial.time_to_ball is None else ' in %.1f s' % trial.time_to_ball)
        else:
            outcome = 'not reached' + ('' if trial.closest is None else ', closest %.2f m' % trial.closest)
        picture = TrialPicture(robot=rows[:, 1:4], ball=rows[:, 4:6], ball_radius=ball_radius,
                               footprint=geometry.footprint if geometry is not None else (),
                               camera=camera, title='trial %d: %s' % (trial.index, outcome))
        image, _frame = render_trial(self.found.world_map, picture)
        name = 'trial_%02d.png' % trial.index
        try:
            write_png(os.path.join(self.spec.out_dir, name), image)
        except FlatsimError:
            return ''
        return name


class SessionTrials:
    """The session's trials: the placements drawn, shared with the extra worlds, and the chase
    item judged from every world's; a part of the session's own world."""

    def placements(self, count):
        """(placements, notes) for the spawned robot in the world flatsim loaded."""
        from flatsim.loading.sdf_world import load_world
        found = self.found
        spawn = (found.spawn_pose.x, found.spawn_pose.y) if found.spawn_pose is not None else (0.0, 0.0)
        plan = placement.plan_placements(load_world(found.world_file, found.model_paths), found.geometry,
                                         count, self.spec.seed, found.ball, keep_out=[found.robot],
                                         spawn=spawn)
        # The view along each trial is judged against the same colliders.
        found.free_space = placement.FreeSpace(load_world(found.world_file, found.model_paths),
                                               keep_out=[found.robot, found.ball])
        return plan

    def prepare_trials(self):
        """What every trial needs: the ball's height, the placements, the states' schedule.
        False (the chase item failed) when the trials cannot run."""
        if not self.world_up():
            self.grade.set('chase', False, 'not run: the world did not launch')
            return False
        if self.found.geometry is None:
            self.grade.set('chase', False, 'not run: no robot_description parameter holds the URDF of '
                           'the spawned robot `%s`, so its outline and camera are unknown' % self.found.robot)
            return False
        sim = chase_graph.SimControl()
        ball_pose = sim.pose(self.found.ball)
        self.found.ball_z = ball_pose[0].position.z if ball_pose else 0.1
        self.read_state_schedule(sim)
        try:
            placements, notes = self.placements(max(self.spec.trials, 1))
        except FlatsimError as error:
            self.grade.not_judged('chase', 'no placement could be drawn in this world: %s' % error)
            self.found.placements_drawn = []
            self.grade.world_png = self.draw_world(sim)
            return False
        self.grade.notes.extend(notes)
        self.found.placements_drawn = placements
        return True

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
                'count_calls': self.counter is not None, 'ball_z': self.found.ball_z,
                'own_service': self.own_service_share(),
                'placements': [asdict(place) for place in self.found.placements_drawn]})
            self.extra_worlds.start_after(worlds.EXTRA_WORLDS_AFTER_S)

    def own_service_share(self):
        """The submission's own service type as the stand-in serves it (type and rebuilt .srv
        text), for an extra world to serve the same; None when it serves the course's."""
        own = self.found.own_service[1] if self.found.own_service else None
        if (self.counter is None or not isinstance(own, service_type.ServiceDefinition)
                or self.counter.srv_type._md5sum != own.md5):
            return None
        return {'type': own.type_name, 'text': service_type.definition_text(own)}

    def run_trials(self):
        """The chase: this world takes trials one by one, the extra worlds take the others as
        they come up (finish_trials gathers theirs)."""
        self.begin_trials()
        if self.found.placements_drawn:
            self.run_share(chase_graph.SimControl())

    def run_share(self, sim):
        """Run trials from the queue in this world until none is left."""
        for index in iter(self.queue.take, None):
            place = self.found.placements_drawn[index]
            trial = rubric.Trial(index, [place.robot_x, place.robot_y, place.robot_yaw],
                                 [place.ball_x, place.ball_y], world=self.spec_world_number())
            self.trials_done[index] = trial
            if not self.alive():
                trial.error = 'world.launch had ended'
                continue
            calls_before = len(self.counter.calls) if self.counter else 0
            self.chase(sim, place, trial)
            if self.counter is not None:
                self.found.trial_calls += len(self.counter.calls) - calls_before

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
                        extra_world={'number': number, 'robot': self.found.robot, 'ball': self.found.ball,
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
        if not self.found.placements_drawn and self.grade.item('chase') is not None:
            return
        extra = self.extra_worlds
        if extra is not None:
            extra.finish()
            self.grade.notes.extend(extra.take_notes())
            if self.queue.pending():
                self.run_share(chase_graph.SimControl())
            for index, (trial, calls) in extra.results.items():
                self.trials_done[index] = trial
                self.found.trial_calls += calls or 0
                self.found.extra_world_calls += calls or 0
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
        elif all(t.error for t in self.grade.trials):
            # Nothing was chased: the trials' errors say why.
            summary = '%sno trial could run; %s' % (rubric.NOT_JUDGED, summary)
        self.grade.set('chase', passed, summary, ['  ' + line for line in why + errors]
                       + (self.excerpt(self.world_log) if errors else []))
