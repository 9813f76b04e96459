"""The studio's WorldAccess over a bare Simulation, without ROS: for tests of new
commands and panels, and for measuring the server's own cost.

Changes go straight to the Simulation under the lock (there is no gazebo_ros
here, so the answers are flatsim's own messages). Reads take the lock too or,
with stepped=True, are handed to the thread stepping the simulation, which
calls run_readers() between steps holding the lock, as the node's loop does.
"""
import collections
import copy
import threading

from flatsim.authoring.world_writer import world_sdf
from flatsim.errors import FlatsimError
from flatsim.pose import Pose
from flatsim.studio.chase import CommandLog
from flatsim.studio.scaling import rescale
from flatsim.studio.world import (Outcome, SnapshotTaker, WorldAccess, describe_scene, find_sensor,
                                  gui_camera_pose, keep_model, model_parts, model_to_insert,
                                  placed_again, skipped_items)

# How long a read waits for the stepping loop before it takes the lock itself.
READ_WAIT = 0.05


class SimWorld(WorldAccess):
    def __init__(self, sim, world_name='test.world', lock=None, stepped=False, world=None):
        """world: the WorldSpec sim was made from, if any (for Save World As)."""
        self.sim = sim
        self.world_name = world_name
        self.world = world
        self.lock = lock or threading.RLock()
        self.stepped = stepped
        self.readers = collections.deque()
        self.snapshots = 0            # how often the studio read the world's poses
        self.snapshot_taker = SnapshotTaker()
        self.scans_wanted = None
        self.command_log = None       # a CommandLog while a chase view is open
        self.service_watch = None     # tests set a ServiceWatch (flatsim.studio.service_watch)

    # -- reads ---------------------------------------------------------------------------
    def read(self, read):
        if not self.stepped:
            with self.lock:
                return read()
        done, found = threading.Event(), []

        def run():
            found.append(read())
            done.set()
        self.readers.append(run)
        if not done.wait(READ_WAIT):
            with self.lock:
                if not found:
                    found.append(read())
        return found[0]

    def run_readers(self):
        """Call between steps, holding the lock."""
        while self.readers:
            self.readers.popleft()()

    def snapshot(self):
        self.snapshots += 1
        return self.read(lambda: self.snapshot_taker.take(self.sim))

    def scene(self):
        return self.read(lambda: describe_scene(self.sim, self.world_name,
                                                gui_camera_pose(self.world)))

    def skipped(self):
        return self.read(lambda: skipped_items(self.sim))

    # -- changes -------------------------------------------------------------------------
    def _change(self, change, done='done'):
        with self.lock:
            try:
                change()
            except FlatsimError as error:
                return Outcome(False, str(error))
        return Outcome(True, done)

    def set_model_pose(self, name, pose):
        return self._change(lambda: self.sim.set_model_state(name, pose))

    def delete_model(self, name):
        return self._change(lambda: self.sim.delete_model(name))

    def copy_model(self, source, name, pose):
        def paste():
            model = copy.deepcopy(self.sim.models[source].source)
            model.name, model.pose = name, Pose()
            self.sim.add_world_model(model, pose)
        return self._change(paste)

    def scale_model(self, name, scale):
        return self._change(lambda: rescale(self.sim, name, scale), 'scaled %s' % name)

    def keep_model(self, name):
        with self.lock:
            parts = model_parts(self.sim, name)
        return keep_model(parts)

    def restore_model(self, kept):
        loaded = copy.deepcopy(kept.loaded)

        def restore():
            if kept.robot:
                model = self.sim.spawn_robot(kept.name, loaded, kept.pose, kept.origin)
            else:
                model = self.sim.add_world_model(loaded, kept.pose, kept.origin)
            placed_again(model, kept)
        return self._change(restore, 'put %s back' % kept.name)

    def insert_model(self, name, sdf, position=None, path=None):
        def insert():
            model, pose, origin = model_to_insert(name, sdf, position, path)
            if model.robot is not None:
                self.sim.spawn_robot(name, model.robot, pose, origin)
            else:
                self.sim.add_world_model(model, pose, origin)
        return self._change(insert, 'inserted %s' % name)

    def world_sdf(self):
        return self.read(lambda: world_sdf(self.sim, self.world))

    def pause(self):
        return self._change(lambda: setattr(self.sim, 'paused', True), 'paused')

    def play(self):
        return self._change(lambda: setattr(self.sim, 'paused', False), 'running')

    def step(self, count):
        def advance():
            for _ in range(count):
                self.sim.paused = False
                self.sim.step()
                self.sim.paused = True
        return self._change(advance, 'stepped %d' % count)

    def reset_model_poses(self):
        return self._change(self.sim.reset_world, 'model poses reset')

    def reset_world(self):
        return self._change(self.sim.reset_time, 'world reset')

    # -- sensors -------------------------------------------------------------------------
    def camera_image(self, sensor):
        with self.lock:
            slot = find_sensor(self.sim, sensor, 'camera')
            return None if slot is None else (self.sim.time, self.sim.sense(slot))

    def want_scans(self, wanted):
        self.scans_wanted = wanted

    def want_commands(self, wanted):
        """Tests add to command_log what a robot's drive would have got."""
        self.command_log = CommandLog() if wanted else None
        if self.service_watch is not None:
            if wanted:
                self.service_watch.open()
            else:
                self.service_watch.close()

    def drive_commands(self, model, now):
        return [] if self.command_log is None else self.command_log.recent(model, now)

    def service_calls(self, now):
        return None if self.service_watch is None else self.service_watch.calls(now)

    def scans(self):
        return []
