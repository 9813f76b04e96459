"""The simulator node's stepping loop: it steps the world at the real-time factor, runs the
reads handed to it between two steps, and starts the world over when physics diverges."""
import threading
import time

import rospy

from flatsim.errors import FlatsimError
from flatsim.names import logged_name
from flatsim.world.physics import MAX_SPEED, MAX_SPIN


class NodeLoop:
    """FlatsimNode's stepping loop; FlatsimNode (flatsim.ros.node) sets up the state it uses."""

    def run(self):
        """Step until shutdown; an unexpected error ends the node instead of freezing time."""
        try:
            self._step_loop()
        except Exception as error:  # noqa: BLE001 - anything here must stop the node visibly
            # Publishing on topics that shutdown has already closed is how a normal exit ends.
            if rospy.core.is_shutdown_requested():
                return
            rospy.logfatal('flatsim: stepping stopped: %r', error)
            rospy.signal_shutdown('stepping stopped: %r' % error)
            raise

    def _step_loop(self):
        self.stepping = True
        # Sim time must never be zero on /clock, or nodes wait for time to start.
        self.publish_clock()
        wall_start, sim_start = time.monotonic(), self.sim.time
        pacing_factor = self.real_time_factor
        while not rospy.is_shutdown():
            with self.lock:
                paused = self.sim.paused
                if not paused:
                    try:
                        self.sim.step()
                    except FlatsimError as error:
                        self.on_diverged(error)
                    self.publish_outputs()
                self.run_readers()
            # Outside the lock, so that the answer (and pause, reset) can come in.
            self.lockstep.hold()
            if paused:
                time.sleep(0.01)
                wall_start, sim_start = time.monotonic(), self.sim.time
                continue
            if self.real_time_factor != pacing_factor:
                # set_physics_properties changed the pace: measure it from now on.
                pacing_factor = self.real_time_factor
                wall_start, sim_start = time.monotonic(), self.sim.time
            if self.real_time_factor > 0:
                lag = (self.sim.time - sim_start) / self.real_time_factor - (time.monotonic() - wall_start)
                if lag > 0:
                    time.sleep(lag)
                elif lag < -0.5:
                    # Too slow to keep up: do not try to catch up in a burst later.
                    wall_start, sim_start = time.monotonic(), self.sim.time

    def read_between_steps(self, read, wait=0.05):
        """read() under the lock, run by the stepping loop between two steps.

        At full speed the loop takes the lock again microseconds after it lets it go, so a
        thread waiting for it is woken and sent back to sleep thousands of times a second,
        which costs the loop more than the read itself. Handed to the loop, the read costs
        one check per step. If the loop does not come round within wait seconds (a lockstep
        hold, a slow frame), or does not run yet, the read takes the lock itself.
        """
        if not self.stepping:
            with self.lock:
                return read()
        job = _Read(read)
        self.readers.append(job)
        if not job.done.wait(wait):
            with self.lock:
                job.run()
        return job.result()

    def run_readers(self):
        while self.readers:
            self.readers.popleft().run()

    def on_diverged(self, error):
        """Bodies pushed past what the solver can hold: the world starts over, and if it
        keeps diverging physics stops with one message instead of a reset every step."""
        recovery = self.sim.recover(error)
        if recovery.dropped_wrenches:
            rospy.logwarn('flatsim: dropped the wrenches on %s, which pushed it past what physics '
                          'holds (apply them again with /gazebo/apply_body_wrench)',
                          ', '.join(logged_name(body) for body in recovery.dropped_wrenches))
        if recovery.stopped:
            rospy.logerr('flatsim: %s again and again: physics paused; delete or move the model, '
                         'or clear the wrenches that push into it (/gazebo/clear_body_wrenches), '
                         'then call /gazebo/unpause_physics', error)
        else:
            rospy.logerr_throttle(1.0, 'flatsim: %s; the world starts over' % error)

    def report_slowed(self):
        if self.sim.physics.slowed:
            rospy.logwarn_throttle(5.0, 'flatsim: %s slowed to flatsim\'s limits (%g m/s, %g rad/s)'
                                   % (', '.join(sorted(self.sim.physics.slowed)), MAX_SPEED, MAX_SPIN))
            self.sim.physics.slowed.clear()


class _Read:
    """A read handed to the stepping loop; run() once, by whichever thread gets to it first."""

    def __init__(self, read):
        self.read = read
        self.done = threading.Event()
        self.claimed = threading.Lock()
        self.value = self.error = None

    def run(self):
        if not self.claimed.acquire(blocking=False):
            return
        try:
            self.value = self.read()
        except Exception as error:  # noqa: BLE001 - handed back to the reader's thread
            self.error = error
        self.done.set()

    def result(self):
        self.done.wait()
        if self.error is not None:
            raise self.error
        return self.value
