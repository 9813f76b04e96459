"""The simulated world: models, robots, fixed-step time and sensor schedules.

No ROS here. The node asks which sensors are due after each step and turns
their output into messages; everything else (physics, drives, raycasts) is
driven from this class so that tests and benchmarks run it without a master.

Models come and go in flatsim.world.model_placing; what is kept of each is in
flatsim.world.sim_models, and their shapes are made in flatsim.world.model_geometry.
"""
import math
from dataclasses import dataclass
from typing import List

import numpy as np
import pymunk

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import MAX_STEP_SIZE, MIN_STEP_SIZE
from flatsim.pose import Pose
from flatsim.sensors.lidar import Lidar
from flatsim.world.model_geometry import is_ground, world_of
from flatsim.world.model_placing import ModelPlacing
from flatsim.world.physics import Physics, check_position, check_twist
from flatsim.world.scene import Scene
from flatsim.world.sim_models import FROM_WORLD, SimRobot, model_origin
from flatsim.world.wrench import Wrenches

# Physics that diverges this often within this many seconds of sim time is stopped.
DIVERGENCE_LIMIT = 3
DIVERGENCE_WINDOW = 1.0


def check_step_size(step_size):
    if not (isinstance(step_size, (int, float)) and MIN_STEP_SIZE <= step_size <= MAX_STEP_SIZE):
        raise FlatsimError('step size must be between %g and %g s, got %r'
                           % (MIN_STEP_SIZE, MAX_STEP_SIZE, step_size))


@dataclass(frozen=True)
class Recovery:
    """What Simulation.recover did after physics diverged."""
    stopped: bool                  # physics paused: it diverged again and again
    dropped_wrenches: List[str]    # the scoped links whose wrenches it dropped


class Simulation(ModelPlacing):
    """A world with its models and robots, advanced in fixed steps."""

    def __init__(self, world=None, step_size=0.002, seed=0):
        check_step_size(step_size)
        self.step_size = step_size
        self.seed = seed
        self.time = 0.0
        self.steps = 0
        # Time at step 0 of the current step size: a new step size keeps time continuous.
        self.time_base = 0.0
        self.paused = False
        self.physics = Physics(step=step_size)
        self.wrenches = Wrenches()
        self.divergences = []      # sim times at which physics diverged lately
        # Counts the changes of where models stand still (moves, arrivals, departures), for
        # readers that keep their poses and for the ground's cache.
        self.layout_version = 0
        self._ground_cache = None
        self.scene = Scene([])
        self.models = {}
        # name -> ModelOrigin of every model, kept as models come and go.
        self.origins = {}
        self.skipped = []
        if world is not None:
            self.skipped.extend(world.skipped)
            # One scene update for the whole world: adding shapes one by one is quadratic.
            pending = []
            for model in world.models:
                if model.robot is None:
                    pending.extend(self._place_world_model(
                        model, model.pose, model_origin(FROM_WORLD, model.element)))
            self._add_prims(pending)
            # Bodies and balls rest on the ground under them, whatever came first in the file.
            for model in self.models.values():
                self._settle(model)
            self.sync_moving_prims()
            for model in world.models:
                if model.robot is not None:
                    self._spawn_saved_robot(model)

    def _add_prims(self, pending):
        """pending: (model, prim) pairs; each model learns the scene indices of its prims."""
        indices = self.scene.extend(prim for _, prim in pending)
        for (model, _), index in zip(pending, indices):
            model.prim_ids.append(index)

    # -- state ------------------------------------------------------------
    def _model(self, name):
        try:
            return self.models[name]
        except KeyError:
            known = ', '.join(sorted(self.models)) or 'none'
            raise FlatsimError('no model named %r (models: %s)' % (name, known)) from None

    def model_pose(self, name):
        model = self._model(name)
        if model.handle is None:
            return model.pose or model.initial_pose
        x, y, yaw = self.physics.pose(model.handle)
        return Pose(x, y, model.z + self._lift(model, x, y), 0.0, 0.0, yaw)

    def _lift(self, model, x, y):
        """How far the ground under (x, y) raises a moving model: robots bolted to the world
        stay where they are."""
        if model.kind == 'robot' and model.handle.body.body_type == pymunk.Body.STATIC:
            return 0.0
        return self.ground_height(x, y)

    def model_twist(self, name):
        """World-frame (vx, vy, wz)."""
        model = self._model(name)
        if model.handle is None:
            return 0.0, 0.0, 0.0
        return self.physics.twist(model.handle)

    def set_model_state(self, name, pose, twist=(0.0, 0.0, 0.0)):
        """Put a model at pose with a world-frame twist (vx, vy, wz).

        A moving model (robot, ball, body) takes x, y and yaw, its height set by
        the ground under it; a model that stands still (static, jointed) takes
        the whole pose, as Gazebo moves a static model, and no twist.
        """
        model = self._model(name)
        values = (pose.x, pose.y, pose.yaw) + tuple(twist)
        if not all(math.isfinite(v) for v in values):
            raise FlatsimError('pose and twist must be finite numbers')
        if model.handle is None:
            self._move_fixed(model, pose)
            return
        # Checked before anything moves, so a refused request changes nothing.
        check_position(name, pose.x, pose.y)
        check_twist(name, *twist)
        self.physics.set_pose(model.handle, pose.x, pose.y, pose.yaw)
        self.physics.set_twist(model.handle, *twist)
        self._sync_model_prims(model)

    def _move_fixed(self, model, pose):
        """A model that stands still, moved by hand: its shapes, colliders and ground go along.
        A refused move changes nothing."""
        if not all(math.isfinite(v) for v in (pose.z, pose.roll, pose.pitch)):
            raise FlatsimError('pose and twist must be finite numbers')
        check_position(model.name, pose.x, pose.y)
        collisions, prims = self._fixed_prims(model.source, pose)
        for prim in prims:
            prim.validate()
        colliders = self._static_colliders(collisions)
        for shape in model.colliders:
            self.physics.remove_static(shape)
        model.colliders = colliders
        model.ground = [prim for prim in collisions if is_ground(prim) and prim.z_max > 0.0]
        for prim_id, prim in zip(model.prim_ids, prims):
            self.scene.replace(prim_id, prim)
        model.pose = pose
        self.layout_version += 1

    def reset_world(self):
        """Every model back to where it started, moving ones at rest; time goes on."""
        for model in self.models.values():
            if model.handle is None and model.pose is not None and model.pose != model.initial_pose:
                self._move_fixed(model, model.initial_pose)
            if model.handle is not None:
                start = model.initial_pose
                self.physics.restart(model.handle, start.x, start.y, start.yaw)
                if isinstance(model, SimRobot) and model.drive is not None:
                    model.drive.reset()
                if isinstance(model, SimRobot) and model.control is not None:
                    model.control.reset()
                self._sync_model_prims(model)

    def recover(self, error=None):
        """After physics diverged (error, a FlatsimError): the world starts over, or stops
        when that keeps happening. The wrenches on the model that diverged are dropped: a
        wrench that lasts would push it over again as soon as the world starts over.

        Returns a Recovery: stopped (physics paused) after DIVERGENCE_LIMIT divergences
        within DIVERGENCE_WINDOW s of sim time, so starting over does not help.
        """
        self.divergences = [t for t in self.divergences if self.time - t < DIVERGENCE_WINDOW]
        self.divergences.append(self.time)
        self.reset_world()
        model = getattr(error, 'model', None)
        dropped = self.wrenches.clear_model(model) if model else []
        stopped = len(self.divergences) >= DIVERGENCE_LIMIT
        if stopped:
            self.paused = True
            self.divergences = []
        return Recovery(stopped, dropped)

    def _lidar(self, config, index):
        """A robot's index-th lidar; its noise follows from the seed alone, so a reset repeats it."""
        return Lidar(config, seed=self.seed + index)

    def reset_time(self):
        """Time back to zero, as gazebo's reset_simulation does, and the world as it started.

        The sensor noise starts over from the seed too, so that the same
        placements after a reset give the same run, bit for bit, whatever
        ran before.
        """
        self.reset_world()
        self.time = 0.0
        self.steps = 0
        self.time_base = 0.0
        for robot in self.robots():
            lasers = (slot for slot in robot.sensors if slot.kind == 'laser')
            for index, slot in enumerate(lasers):
                slot.impl = self._lidar(slot.config, index)
            for slot in robot.sensors:
                slot.next_due = 0.0

    def robots(self):
        return [m for m in self.models.values() if isinstance(m, SimRobot)]

    # -- time -------------------------------------------------------------
    def step(self):
        """Advance one fixed step (nothing moves while paused)."""
        if self.paused:
            return
        for robot in self.robots():
            if robot.control is not None:
                robot.control.step(self.time, self.step_size)
        self.wrenches.apply(self)
        self.physics.step()
        self.steps += 1
        self.time = self.time_base + self.steps * self.step_size

    def set_step_size(self, step_size):
        """A new fixed step from now on; time goes on from where it is."""
        check_step_size(step_size)
        self.time_base, self.steps = self.time, 0
        self.step_size = self.physics.step_size = float(step_size)

    def due_sensors(self):
        """Sensors whose next update time has come; each is rescheduled."""
        due = []
        for robot in self.robots():
            for slot in robot.sensors:
                if self.time + 1e-9 >= slot.next_due:
                    due.append(slot)
                    # Keep a fixed cadence: skipped updates are not made up. A rate above
                    # the physics rate means every step.
                    step = max(slot.period, self.step_size)
                    missed = math.floor((self.time + 1e-9 - slot.next_due) / step) + 1
                    slot.next_due += max(missed, 1) * step
                    if slot.next_due <= self.time + 1e-9:  # too far ahead for the float's precision
                        slot.next_due = self.time + step
        return due

    def sensor_pose(self, slot):
        base = self.physics.pose(slot.robot.handle)
        height = slot.robot.z + self._lift(slot.robot, base[0], base[1])
        control = slot.robot.control
        if control is not None:
            # On a moving link: the link where the joints are now, then the sensor on it.
            return world_of(base, height, control.link_pose(slot.config.link) * slot.config.pose)
        return world_of(base, height, slot.mount)

    def sense(self, slot):
        """The sensor's output now: an image array or an array of ranges."""
        self.sync_moving_prims()
        pose = self.sensor_pose(slot)
        # A robot's own shapes neither hide its camera's view nor block its lidar.
        own = slot.robot.prim_ids or None
        if slot.kind == 'camera':
            return slot.impl.render(self.scene, pose.x, pose.y, pose.z, pose.yaw, exclude=own,
                                    pitch=pose.pitch, roll=pose.roll)
        return slot.impl.scan(self.scene, pose.x, pose.y, pose.z, pose.yaw, exclude=own)

    def sync_moving_prims(self):
        """Bring the balls' and bodies' scene primitives to their bodies' poses.

        They are moved only when something looks at the scene (a sensor, the
        overhead view, the markers), not on every physics step.
        """
        for model in self.models.values():
            if model.kind in ('ball', 'body', 'robot'):
                self._sync_model_prims(model)

    def _sync_model_prims(self, model):
        if model.kind not in ('ball', 'body', 'robot') or not model.prim_ids or model.handle is None:
            return
        x, y, yaw = self.physics.pose(model.handle)
        c, s = math.cos(yaw), math.sin(yaw)
        offsets = np.asarray(model.prim_offsets, dtype=float).reshape(-1, 3)
        self.scene.set_poses(model.prim_ids, x + c * offsets[:, 0] - s * offsets[:, 1],
                             y + s * offsets[:, 0] + c * offsets[:, 1], yaw + offsets[:, 2])
        if model.kind in ('ball', 'body'):
            # A robot's shapes are placed at its spawn height, which already stands on the ground.
            lift = self.ground_height(x, y) if self.has_ground() else 0.0
            for prim_id, (z_min, z_max) in zip(model.prim_ids, model.prim_heights):
                self.scene.set_height(prim_id, z_min + lift, z_max + lift)
