"""Chase trials shared among worlds. No ROS here: the worlds are processes.

The session's own world runs the trials one after the other. With --worlds N,
once it has chased for EXTRA_WORLDS_AFTER_S with trials left, N-1 extra
worlds come up beside it, each a process of its own (trial_world.TrialWorld) in
the session's network namespace: its own master on its own port, the
submission's world.launch and ball_chaser.launch as the session's own world
prepared them, in the same sandbox and within the same limits. Whichever
world is free takes the next trial (TrialQueue). Each trial starts from a
reset with both models placed, in lockstep, so a trial comes out the same in
whichever world runs it.

worlds_for() chooses N from what this process may use: its CPUs (a cluster
job's cpuset), the memory limit and the process limit of the submission.
"""
import collections
import json
import os
import signal
import socket
import subprocess
import threading

from chase_tools.grading import rubric
from chase_tools.procs import wait_or_kill

# What one world holds of the submission's limits: the simulator, robot_state_publisher,
# joint_state_publisher, gzclient, two roslaunch and the submission's two nodes. The test
# fixtures' world (a 320x240 camera) peaked at 274 MiB and 54 tasks in its cgroup; a course
# robot's 800x800 camera and a student's nodes take more, so with room to spare:
MEMORY_PER_WORLD = 1 << 30
PROCESSES_PER_WORLD = 250
# A chase in lockstep keeps about one and a half cores busy (the simulator and the
# submission's nodes). On two cores, at a load of 2 from other work, a second world saved
# nothing on three one-minute trials and 8 % on three four-minute ones (bench/bench_grade.py),
# and two chases sharing two cores wait longer for their nodes' answers: a world is given two.
CORES_PER_WORLD = 2
# The most worlds one grade runs: each world's roscore and simulator have uids of their own,
# which the session's user namespace maps (session_user.py).
MAX_WORLDS = 8
# Wall seconds the session's own world chases before the extra worlds start. About what an
# extra world takes to come up on an idle two-core machine: trials that are over sooner would
# only be slowed by one coming up beside them.
EXTRA_WORLDS_AFTER_S = 4.0
# Wall seconds an extra world has to stop its launches and its master.
STOP_S = 30.0


def worlds_for(trials, cores, memory, processes):
    """How many worlds share the trials: as many as the cores, the memory limit and the process
    limit hold, and no more than there are trials or MAX_WORLDS; at least one."""
    fits = min(cores // CORES_PER_WORLD, memory // MEMORY_PER_WORLD, processes // PROCESSES_PER_WORLD,
               MAX_WORLDS)
    return max(1, min(trials, fits))


def free_port():
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


class TrialQueue:
    """The indices of the trials not yet taken, handed out in order to whichever world asks."""

    def __init__(self, indices):
        self._pending = collections.deque(indices)
        self._lock = threading.Lock()

    def take(self):
        """The next trial's index, or None when every trial is taken."""
        with self._lock:
            return self._pending.popleft() if self._pending else None

    def give_back(self, index):
        """A trial a world could not run: the next world to ask runs it."""
        with self._lock:
            self._pending.appendleft(index)

    def pending(self):
        with self._lock:
            return list(self._pending)


class ExtraWorlds:
    """The extra worlds' processes, and a thread each that hands it trials from the queue.

    They start as soon as the session's own world is up, so that theirs come up
    while it checks the sensors and the service; begin_chase() hands them what
    the chase needs (the launch files as prepared, the placements) and the queue.
    commands: {number: (command, log path)}; say(text) reports progress (the
    session log). The trials they ran end up in results {index: (rubric.Trial,
    calls counted during it)}, what they had to say in take_notes().
    """

    def __init__(self, commands, say=lambda text: None):
        self.commands = commands
        self.say = say
        self.queue = None
        self.chase = None               # what begin_chase() handed over, None for no chase
        self.chase_begun = threading.Event()
        self.results = {}
        self.notes = []
        self.procs = {}
        self.up = set()                 # the worlds that came up with the chaser
        self.threads = {}
        self.lock = threading.Lock()
        self.closing = False
        self.timer = None
        self.starting = False           # start() is under way

    def start(self):
        for number, (cmd, log_path) in sorted(self.commands.items()):
            with open(log_path, 'w') as log:
                proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=log, text=True, start_new_session=True)
            self.procs[number] = proc
            thread = threading.Thread(target=self._serve, args=(number, proc), daemon=True,
                                      name='world_%d' % number)
            thread.start()
            self.threads[number] = thread
        self.say('%d extra world%s coming up' % (len(self.procs), '' if len(self.procs) == 1 else 's'))

    def start_after(self, seconds):
        """start() in seconds, if trials are left then; finish() and stop() call it off."""
        def start_if_needed():
            with self.lock:
                if self.closing or not self.queue.pending():
                    return
                self.starting = True
            self.start()
        self.timer = threading.Timer(seconds, start_if_needed)
        self.timer.daemon = True
        self.timer.start()

    def begin_chase(self, queue, chase):
        """The trials can begin: each world takes them from queue once it is up; chase is the
        message that brings up its chaser ({"chase": chase})."""
        self.queue, self.chase = queue, chase
        self.chase_begun.set()

    def _note(self, *texts):
        with self.lock:
            self.notes += texts

    def take_notes(self):
        """What the worlds said since the last call."""
        with self.lock:
            notes, self.notes = self.notes, []
        return notes

    def _not_up(self, number, answer):
        self._note(*answer.get('notes', []))
        if self.closing:
            self._note('world %d was stopped before it came up: the other worlds had run every '
                       'trial' % number)
        else:
            self._note('world %d did not come up (%s), so it ran no trial; see logs/world_%d/'
                       % (number, answer.get('failed', 'it ended'), number))

    def _serve(self, number, proc):
        answer = _read(proc)
        if not answer.get('world_up'):
            self._not_up(number, answer)
            return
        self.chase_begun.wait()
        if self.chase is None or not _send(proc, {'chase': self.chase}):
            _send(proc, {'stop': True})
            return
        answer = _read(proc)
        if not answer.get('ready'):
            self._not_up(number, answer)
            return
        with self.lock:
            self.up.add(number)
        self.say('world %d is up' % number)
        for index in iter(self.queue.take, None):
            if not _send(proc, {'run': index}):
                self.queue.give_back(index)
                break
            answer = _read(proc)
            if 'trial' in answer:
                with self.lock:
                    self.results[index] = (rubric.Trial(**answer['trial']), answer.get('calls'))
                continue
            self.queue.give_back(index)
            self._note('world %d could not run trial %d (%s); another world ran it'
                       % (number, index, answer.get('why', 'it ended')))
            break
        _send(proc, {'stop': True})

    def _close(self):
        """No world starts from now on; one that start_after() is starting has its process."""
        with self.lock:
            self.closing = True
            starting = self.starting
        if self.timer is not None:
            self.timer.cancel()
            if starting:
                self.timer.join()
        self.chase_begun.set()

    def finish(self):
        """Every trial has been taken: wait for those the extra worlds still run. A world not
        yet up is stopped, having nothing left to do."""
        self._close()
        with self.lock:
            up = set(self.up)
        for number, proc in self.procs.items():
            if number not in up:
                _interrupt(proc)
        for number in up:
            self.threads[number].join()

    def stop(self):
        """Each extra world stops its launches and master (now, if the grade was stopped);
        their last notes."""
        self._close()
        with self.lock:
            busy = [number for number in self.up if self.threads[number].is_alive()]
        for number in busy:
            _interrupt(self.procs[number])
        for number, proc in sorted(self.procs.items()):
            self.threads[number].join()
            self._note(*_read(proc).get('notes', []))
            wait_or_kill(proc, STOP_S)
        self.procs = {}


def _interrupt(proc):
    if proc.poll() is None:
        try:
            os.kill(proc.pid, signal.SIGINT)
        except ProcessLookupError:
            pass


def _send(proc, message):
    try:
        proc.stdin.write(json.dumps(message) + '\n')
        proc.stdin.flush()
        return True
    except (BrokenPipeError, OSError, ValueError):
        return False


def _read(proc):
    """The world's next message, {} once it has ended."""
    try:
        line = proc.stdout.readline()
        return json.loads(line) if line.strip() else {}
    except (OSError, ValueError):
        return {}

