"""Lockstep: after a camera frame, sim time waits for the robot's controller to react.

No rospy here: the node tells a Lockstep when a frame went out and when a
drive command came in, and holds its stepping thread in hold().

The reaction to a frame is the first command on the robot's drive command
topic (cmd_vel) after the frame was published. Once it came, the hold goes on
while more commands follow within a quiet time of each other: a node that
sends "move" and then "stop" from one callback has finished with the frame
only after the stop, and time runs on with the stop in effect, as it would in
real time, where the move would act only for the moment between the two. The
quiet time is `quiet`, or twice the longest follow-up the controller has
sent (QuietBound): a command that comes after the hold and before the next
frame is one, and teaches the next holds to wait for it. A controller that
answered each of its last frames with the same number of commands (one, or a
move and a stop) is instead waited for until that many have come, however far
apart the scheduler puts them, and time runs on at its last one without a
quiet time. Until a controller has answered that many frames, its quiet time
is at least ten times `quiet`, since whether a stop follows its move is not
known yet. How long to wait for
the first command is learned per robot by a ReactionBound:
- a new controller, or one that answered each of its last frames (up to
  ten), is waited for up to max_wait: it answers every frame, so a late
  answer is a slow one;
- a controller that stays silent now and then (many course nodes call
  drive_bot only when their decision changes) is waited for a few times its
  usual reaction time, so its silent frames cost little wall time;
- a controller that has never answered is waited for min_wait.
A killed controller therefore costs one max_wait, then min_wait per frame.
"""
import collections
import threading
import time

import numpy as np

from flatsim.errors import FlatsimError

# Reaction times kept to learn the bound from.
WINDOW = 50
# How many of a controller's last frames tell whether it answers every frame.
TRUST_FRAMES = 10
# The bound for a controller that is silent now and then: this times its p90 reaction time.
MARGIN = 3.0
# Wall seconds without a further command after which a frame's answer is complete, unless
# the controller has shown that its answers take longer (QuietBound).
DEFAULT_QUIET_S = 0.01
# Commands this close (wall s) are one callback's: a node that publishes on a timer of its
# own sends them farther apart, and must not stretch every hold.
FOLLOW_UP_MAX_S = 0.03
# The quiet time learned from a controller's follow-ups: this times the longest of them.
QUIET_MARGIN = 2.0
# The longest a frame's answer is waited on once its first command came (wall s): a node that
# publishes faster than its quiet time, whatever the frames, holds each frame this long at most.
ANSWER_MAX_S = 0.1
# Until a controller has answered TRUST_FRAMES frames, its quiet time is at least this many
# times the floor (up to ANSWER_MAX_S): whether a second command follows is not known yet, and on a
# loaded machine a rospy node's two service calls from one callback came up to 45 ms apart,
# while the move would act. With the default quiet time this costs a new controller about a
# second of wall time.
LEARNING_QUIET_FACTOR = 10.0
# The longest the rest of an answer is waited for when the controller's last frames each had
# that many commands (wall s): a loaded machine puts 30 ms and more between a rospy node's two
# service calls, and a pattern that changes costs this once.
WHOLE_ANSWER_MAX_S = 0.5


class ReactionBound:
    """The wall time to wait for one controller's reaction to a frame, from what it did before."""

    def __init__(self, max_wait=1.0, min_wait=0.005):
        if not (max_wait > 0 and 0 < min_wait <= max_wait):
            raise FlatsimError('lockstep waits must satisfy 0 < min_wait <= max_wait, got %r, %r'
                             % (min_wait, max_wait))
        self.max_wait = max_wait
        self.min_wait = min_wait
        self.reaction_times = collections.deque(maxlen=WINDOW)
        self.answered = collections.deque(maxlen=TRUST_FRAMES)

    def record(self, reaction_time):
        """One frame's outcome: the wall seconds until the reaction, or None if none came."""
        self.answered.append(reaction_time is not None)
        if reaction_time is not None:
            self.reaction_times.append(reaction_time)

    def bound(self):
        if all(self.answered):
            # New, or it answered each of the last frames: worth waiting for.
            return self.max_wait
        if not self.reaction_times:
            return self.min_wait
        usual = float(np.percentile(self.reaction_times, 90))
        return min(self.max_wait, max(self.min_wait, MARGIN * usual))


class QuietBound:
    """How long to wait for a controller's next command once it answered a frame: `floor`, or
    QUIET_MARGIN times the longest follow-up it sent (a command within FOLLOW_UP_MAX_S of its
    previous one in the same answer: "move", then "stop" from one callback) over its last
    WINDOW follow-ups. A rospy node that calls a service twice from one callback answers in
    two parts some 10 to 20 ms apart."""

    def __init__(self, floor):
        self.floor = floor
        self.follow_ups = collections.deque(maxlen=WINDOW)

    def record(self, gap):
        if 0.0 <= gap <= FOLLOW_UP_MAX_S:
            self.follow_ups.append(gap)

    def quiet(self):
        if not self.follow_ups:
            return self.floor
        return max(self.floor, QUIET_MARGIN * max(self.follow_ups))


class Lockstep:
    """Counts drive commands per robot and holds the stepping thread until frames are answered.

    Thread safety: commands come from subscriber threads, holds from the
    stepping thread, interrupts from service threads; one condition guards it all.
    """

    def __init__(self, enabled=False, max_wait=1.0, min_wait=0.005, clock=time.monotonic,
                 quiet=DEFAULT_QUIET_S):
        ReactionBound(max_wait, min_wait)  # refuses bad limits now rather than at the first frame
        if not 0.0 <= quiet <= max_wait:
            raise FlatsimError('the lockstep quiet time must lie within 0..max_wait (%r), got %r'
                               % (max_wait, quiet))
        self.enabled = enabled
        self.max_wait = max_wait
        self.min_wait = min_wait
        self.quiet = quiet
        self.clock = clock
        self._cond = threading.Condition()
        self._commands = collections.Counter()
        self._arrival = {}
        self._pending = []
        self._bounds = {}
        self._quiet = {}
        self._answering = set()     # robots whose answer to their last frame may go on
        self._frame_base = {}       # robot: its command count when its last frame went out
        self._answer_sizes = {}     # robot: commands in each of its last answered frames
        self._epoch = 0

    def bound_for(self, robot):
        bound = self._bounds.get(robot)
        if bound is None:
            bound = self._bounds[robot] = ReactionBound(self.max_wait, self.min_wait)
        return bound

    def quiet_for(self, robot):
        quiet = self._quiet.get(robot)
        if quiet is None:
            quiet = self._quiet[robot] = QuietBound(self.quiet)
        return quiet

    def commands_per_answer(self, robot):
        """How many commands the robot's controller answers a frame with, if each of its last
        TRUST_FRAMES answered frames had the same number; else None."""
        sizes = self._answer_sizes.get(robot, ())
        if len(sizes) == TRUST_FRAMES and len(set(sizes)) == 1:
            return sizes[0]
        return None

    def command_arrived(self, robot):
        with self._cond:
            now = self.clock()
            if robot in self._answering and robot in self._arrival:
                # Before its next frame: more of the answer to the last one.
                self.quiet_for(robot).record(now - self._arrival[robot])
            self._commands[robot] += 1
            self._arrival[robot] = now
            self._cond.notify_all()

    def frame_sent(self, robot):
        """Call just before publishing a frame the robot's controller reacts to; returns its token.

        The frame is pending until hold() has waited for its answer.
        """
        with self._cond:
            count = self._commands[robot]
            answered = count - self._frame_base.get(robot, count)
            if answered:
                self._answer_sizes.setdefault(robot, collections.deque(maxlen=TRUST_FRAMES)).append(answered)
            self._frame_base[robot] = count
            token = (robot, count, self.clock())
            self._pending.append(token)
            self._answering.discard(robot)
            return token

    def interrupt(self):
        """End any hold now: a reset, lockstep turned off, shutdown."""
        with self._cond:
            self._epoch += 1
            self._pending = []
            self._cond.notify_all()

    def new_controllers(self):
        """The controllers were started afresh: each is waited for as a new one (up to
        max_wait) until it shows otherwise, whatever the ones before it did."""
        with self._cond:
            self._bounds.clear()
            self._answer_sizes.clear()
            self._frame_base.clear()

    def forget(self, robot):
        """A robot is gone: its learned bound goes with it, and no hold waits for it."""
        with self._cond:
            self._bounds.pop(robot, None)
            self._quiet.pop(robot, None)
            self._answering.discard(robot)
            self._frame_base.pop(robot, None)
            self._answer_sizes.pop(robot, None)
            self._commands.pop(robot, None)
            self._arrival.pop(robot, None)
            self._epoch += 1
            self._pending = []
            self._cond.notify_all()

    def _await_answer(self, robot, count, sent, epoch):
        """Hold on, after the first command answering the frame sent at `sent` (with the
        robot's command count then `count`), until the rest of the answer has come; False if
        an interrupt came. Called with the condition held."""
        arrived = self._arrival[robot]
        size = self.commands_per_answer(robot)
        if size is None:
            return self._await_quiet(robot, min(sent + self.max_wait, arrived + ANSWER_MAX_S), epoch)
        self._answering.add(robot)
        limit = min(sent + self.max_wait, arrived + WHOLE_ANSWER_MAX_S)
        while self._commands[robot] < count + size:
            if self._epoch != epoch:
                return False
            remaining = limit - self.clock()
            if remaining <= 0:
                break
            self._cond.wait(remaining)
        return True

    def quiet_time(self, robot):
        """How long after the robot's last command its answer is complete: its QuietBound's
        quiet time, and at least LEARNING_QUIET_FACTOR times the floor until it has answered
        TRUST_FRAMES frames."""
        quiet = self.quiet_for(robot).quiet()
        if len(self._answer_sizes.get(robot, ())) < TRUST_FRAMES:
            return max(LEARNING_QUIET_FACTOR * self.quiet, quiet)
        return quiet

    def _await_quiet(self, robot, limit, epoch):
        """Hold on while the robot's commands follow each other within its quiet time
        (quiet_time), up to limit (wall clock); False if an interrupt came. Called with the
        condition held."""
        self._answering.add(robot)
        while True:
            seen = self._commands[robot]
            until = min(self._arrival[robot] + self.quiet_time(robot), limit)
            while self._commands[robot] == seen:
                if self._epoch != epoch:
                    return False
                remaining = until - self.clock()
                if remaining <= 0:
                    return True
                self._cond.wait(remaining)

    def settle(self, wall_timeout):
        """Wait until no frame is pending: its answer has come, or its wait ran out.

        A pause calls this, so that when the pause returns no answer is still on its way.
        """
        deadline = self.clock() + wall_timeout
        with self._cond:
            while self._pending:
                remaining = deadline - self.clock()
                if remaining <= 0:
                    return False
                self._cond.wait(remaining)
        return True

    def hold(self):
        """Wait until every pending frame has been answered or its bound has passed.

        Returns {robot: reaction seconds or None}. An interrupt ends the hold
        at once and leaves the bounds unchanged.
        """
        outcome = {}
        with self._cond:
            epoch = self._epoch
            for robot, count, sent in self._pending:
                limit = sent + self.bound_for(robot).bound()
                while self._commands[robot] == count and self._epoch == epoch:
                    remaining = limit - self.clock()
                    if remaining <= 0:
                        break
                    self._cond.wait(remaining)
                if self._epoch != epoch:
                    return {}
                answered = self._commands[robot] != count
                outcome[robot] = self._arrival[robot] - sent if answered else None
                if answered and not self._await_answer(robot, count, sent, epoch):
                    return {}
            for robot, reaction in outcome.items():
                self.bound_for(robot).record(reaction)
            self._pending = []
            self._cond.notify_all()
        return outcome
