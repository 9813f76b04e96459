"""How models come into the simulation and leave it: world models as colliders, balls and
bodies that robots push; robots with their drives and sensors; the ground they rest on.
No ROS here."""
import math

from flatsim.errors import FlatsimError, Skipped
from flatsim.loading.urdf_robot import link_pose
from flatsim.pose import Pose
from flatsim.sensors.camera import PinholeCamera
from flatsim.world.drive import RosControlWheels, make_drive
from flatsim.world.model_geometry import (WORKING_HEIGHT, body_inertia, geom_prims, is_ground, is_obstacle,
                                          robot_prims, root_height)
from flatsim.world.robot_control import RobotControl
from flatsim.world.sim_models import (FROM_SDF, FROM_URDF, FROM_WORLD, ModelOrigin, SensorSlot, SimModel,
                                      SimRobot, model_origin)

# A sphere this small or smaller is a ball the robot can push.
MAX_BALL_RADIUS = 0.5
# A ros_control velocity joint's wheel counts as on the floor when its bottom is this close to
# the robot's lowest point (m).
WHEEL_FLOOR_TOLERANCE = 0.01
# A collision's friction coefficient against the ground when its <surface> gives none: ODE's <mu>.
DEFAULT_FRICTION = 1.0


def _covers(prim, x, y):
    """Whether the prim's footprint holds the point (x, y)."""
    dx, dy = x - prim.x, y - prim.y
    if prim.kind == 'box':
        c, s = math.cos(prim.yaw), math.sin(prim.yaw)
        return abs(c * dx + s * dy) <= prim.half_x and abs(-s * dx + c * dy) <= prim.half_y
    return dx * dx + dy * dy <= prim.radius * prim.radius


class ModelPlacing:
    """Simulation's arrivals and departures of models; Simulation (flatsim.world.sim) sets up
    the state they use."""

    # -- building the world ----------------------------------------------
    def add_world_model(self, model, pose=None, origin=None):
        """Add an SDF model: statics and jointed models become colliders, small dynamic
        spheres balls, other dynamic models bodies that robots and balls push.

        origin (a ModelOrigin) says where it came from; by default a spawned SDF.
        """
        pending = self._place_world_model(model, pose or model.pose,
                                          origin or model_origin(FROM_SDF, model.element))
        sim_model = self.models[model.name]
        try:
            self._add_prims(pending)
            self._settle(sim_model)
            self._sync_model_prims(sim_model)
        except Exception:
            self.delete_model(model.name)
            raise
        return sim_model

    def _place_world_model(self, model, pose, origin, hold=''):
        """Register a model and its colliders; returns its (model, prim) pairs for the scene.

        A dynamic model becomes a body that robots and balls push, unless it is
        jointed (its joints would move its links apart, which one body in the
        plane cannot) or hold is set; such a model, and every static one, stands
        where it is put until it is moved by hand (set_model_state, the studio).
        hold: why to hold a dynamic model still, said before (a saved robot that cannot run).

        A model that cannot be placed leaves nothing behind: no collider, no origin (which
        Save World As would write a model for) and no entry in models.
        """
        if model.name in self.models:
            raise FlatsimError('a model named %r already exists' % model.name)
        joints = getattr(model, 'joints', 0)
        if not model.static and not hold and joints:
            # The loader has said so.
            hold = ('its %d joint(s) would take its links apart, and flatsim moves a model as '
                    'one rigid body in the plane' % joints)
        if not model.static and not hold:
            ball = self._ball_geom(model)
            pending = (self._place_ball(model, pose, ball) if ball is not None
                       else self._place_body(model, pose))
            if pending is not None:
                self.origins[model.name] = origin
                return pending
            hold = ('no collision of it stands in the working height (%g to %g m above the '
                    'ground) for anything to push' % WORKING_HEIGHT)
            self.skipped.append(Skipped('model %s' % model.name, '%s; held still' % hold))
        sim_model = SimModel(model.name, 'static', pose, pose=pose, source=model, held=hold)
        pending = self._place_fixed(sim_model, pose)
        self.models[model.name] = sim_model
        self.layout_version += 1
        self.origins[model.name] = origin
        return pending

    def _place_fixed(self, sim_model, pose):
        """The colliders and ground of a model that stands still at pose; its (model, prim) pairs."""
        collisions, prims = self._fixed_prims(sim_model.source, pose)
        sim_model.colliders = self._static_colliders(collisions)
        sim_model.ground = [prim for prim in collisions if is_ground(prim) and prim.z_max > 0.0]
        return [(sim_model, prim) for prim in prims]

    @staticmethod
    def _fixed_prims(model, pose):
        """(its collision prims, all its prims: collisions then visuals) of a model at pose."""
        collisions = geom_prims(model.name, pose, model.collisions, 'lidar')
        return collisions, collisions + geom_prims(model.name, pose, model.visuals, 'camera')

    def _static_colliders(self, collisions):
        """Static physics shapes for the obstacles among collisions; none are left on failure."""
        colliders = []
        try:
            for prim in filter(is_obstacle, collisions):
                if prim.kind == 'box':
                    shape = self.physics.add_static_box(prim.x, prim.y, prim.yaw, prim.half_x,
                                                        prim.half_y)
                else:
                    shape = self.physics.add_static_circle(prim.x, prim.y, prim.radius)
                colliders.append(shape)
        except Exception:
            for shape in colliders:
                self.physics.remove_static(shape)
            raise
        return colliders

    @staticmethod
    def _ball_geom(model):
        spheres = [g for g in model.collisions if g.kind == 'sphere']
        others = [g for g in model.collisions if g.kind != 'sphere']
        if len(spheres) == 1 and not others and spheres[0].size[0] <= MAX_BALL_RADIUS:
            return spheres[0]
        return None

    def _place_ball(self, model, pose, geom):
        radius = geom.size[0]
        handle = self.physics.add_ball(model.name, pose.x, pose.y, radius, model.mass or 1.0)
        sim_model = SimModel(model.name, 'ball', pose, handle=handle, z=pose.z, source=model)
        # Prims are made at the model origin, and their offsets kept, so that they follow the body.
        try:
            prims = (geom_prims(model.name, Pose(z=pose.z), model.collisions, 'lidar')
                     + geom_prims(model.name, Pose(z=pose.z), model.visuals, 'camera'))
        except Exception:
            self.physics.remove(handle)
            raise
        self._follow_body(sim_model, prims)
        self.models[model.name] = sim_model
        return [(sim_model, prim) for prim in prims]

    def _place_body(self, model, pose):
        """A dynamic model as one body in the plane, pushed by whatever runs into it and
        braked by its friction on the ground; None when nothing of it would be pushed."""
        # Made with the model's roll and pitch but no yaw: the body's angle turns them.
        upright = Pose(0.0, 0.0, pose.z, pose.roll, pose.pitch, 0.0)
        collisions = geom_prims(model.name, upright, model.collisions, 'lidar')
        blocking = [prim for prim in collisions if is_obstacle(prim)]
        if not blocking:
            return None
        prims = collisions + geom_prims(model.name, upright, model.visuals, 'camera')
        centre, moment = body_inertia(model, upright)
        handle = self.physics.add_body(model.name, blocking, model.mass or 1.0, moment, centre,
                                       pose.x, pose.y, pose.yaw,
                                       getattr(model, 'friction', DEFAULT_FRICTION))
        sim_model = SimModel(model.name, 'body', pose, handle=handle, z=pose.z, source=model)
        self._follow_body(sim_model, prims)
        self.models[model.name] = sim_model
        return [(sim_model, prim) for prim in prims]

    @staticmethod
    def _follow_body(sim_model, prims):
        """Keep each prim's place on the body, so that it follows the body as it moves."""
        sim_model.prim_offsets = [(prim.x, prim.y, prim.yaw) for prim in prims]
        sim_model.prim_heights = [(prim.z_min, prim.z_max) for prim in prims]

    def _ground(self):
        """Every model's ground prims, gathered once after each change of the world's layout."""
        key = (len(self.models), self.layout_version)
        if self._ground_cache is None or self._ground_cache[0] != key:
            self._ground_cache = (key, [prim for model in self.models.values()
                                        for prim in model.ground])
        return self._ground_cache[1]

    def has_ground(self):
        """Whether any model holds ground (a slab robots drive onto)."""
        return bool(self._ground())

    def ground_height(self, x, y):
        """Height of the ground at (x, y): the top of the highest slab there that robots
        drive onto (see is_ground), else 0, the floor."""
        height = 0.0
        for prim in self._ground():
            if prim.z_max > height and _covers(prim, x, y):
                height = prim.z_max
        return height

    def _settle(self, model):
        """A body or ball placed over ground (a slab) rests on it: its height is kept above
        the ground under it, and one placed into the slab comes up onto it, as Gazebo's
        contacts push it up."""
        start = model.initial_pose
        ground = self.ground_height(start.x, start.y)
        if ground <= 0.0 or not model.prim_heights:
            return
        bottom = min(z_min for z_min, _ in model.prim_heights)
        drop = min(ground, bottom)
        model.z -= drop
        model.prim_heights = [(z_min - drop, z_max - drop) for z_min, z_max in model.prim_heights]

    def spawn_robot(self, name, spec, pose, origin=None):
        """Put a robot (a loaded RobotSpec) on the floor at pose (x, y, yaw are used).

        origin (a ModelOrigin) defaults to a spawned SDF for a robot read from
        SDF, else to a robot from URDF.

        A world saved from Gazebo with the robot in it holds a copy of that
        robot: running (saved) or, when flatsim cannot read it as a robot, a
        plain model. A robot spawned under the same name takes its place, so
        the saved copy does not stand in the way. A spawn that fails leaves the
        copy where it was, as Gazebo leaves its world when a spawn fails.
        """
        existing = self.models.get(name)
        if existing is not None and not self.robot_may_replace(name):
            raise FlatsimError('a model named %r already exists' % name)
        if len(spec.footprint) < 3:
            raise FlatsimError('robot %r has no collision geometry to stand on' % name)
        drive = make_drive(spec.drive) if spec.drive is not None else None
        # A URDF rooted at a link called world is fixed to the world, as in Gazebo.
        fixed = spec.root_link == 'world'
        robot = SimRobot(name, 'robot', pose, z=pose.z if fixed else root_height(spec), spec=spec,
                         drive=drive)
        if spec.ros_control is not None:
            robot.control = RobotControl(spec, self.step_size)
            if drive is None:
                drive = robot.drive = self._ros_control_wheels(spec, robot.control)
        for index, cfg in enumerate(spec.cameras):
            robot.sensors.append(self._slot('camera', cfg, robot, PinholeCamera(cfg)))
        for index, cfg in enumerate(spec.lasers):
            robot.sensors.append(self._slot('laser', cfg, robot, self._lidar(cfg, index)))
        # The copy's body holds the name in physics: it steps aside for the new body and comes
        # back, where it was and as it was moving, if the new one cannot be placed.
        prims = robot_prims(name, spec, robot.z)
        if existing is not None:
            self._withdraw_physics(existing)
        try:
            robot.handle = self.physics.add_robot(name, spec.footprint, spec.mass or 1.0,
                                                  pose.x, pose.y, pose.yaw, drive, fixed=fixed)
        except Exception:
            if existing is not None:
                self._restore_physics(existing)
            raise
        if existing is not None:
            self._forget(existing)
            self.skipped.append(Skipped('model %s' % name, 'replaced by the robot spawned under that name'))
        self.models[name] = robot
        robot.prim_offsets = [(prim.x, prim.y, prim.yaw) for prim in prims]
        self._add_prims([(robot, prim) for prim in prims])
        self._sync_model_prims(robot)
        if origin is None:
            sdf_model = getattr(spec, 'sdf_model', None)
            origin = model_origin(FROM_SDF, sdf_model) if sdf_model is not None else ModelOrigin(FROM_URDF)
        self.origins[name] = origin
        return robot

    @staticmethod
    def _ros_control_wheels(spec, control):
        """ros_control's velocity joints whose wheels reach the floor, as a drive; or None."""
        floor = -root_height(spec)
        wheels = [wheel for wheel in spec.ros_control.wheels
                  if abs(wheel.z - wheel.radius - floor) < WHEEL_FLOOR_TOLERANCE]
        return RosControlWheels(control, wheels) if wheels else None

    def robot_may_replace(self, name):
        """Whether a robot spawned under name takes the place of the model of that name: a
        copy of a robot saved in the world (running or not), or a model that no robot drives."""
        model = self.models[name]
        if model.saved or model.kind == 'static':
            return True
        origin = self.origins.get(name)
        return model.kind == 'body' and origin is not None and origin.kind == FROM_WORLD

    def _spawn_saved_robot(self, model):
        """A robot saved in the world file runs as if spawned, until one is spawned in its place."""
        origin = model_origin(FROM_WORLD, model.element)
        try:
            robot = self.spawn_robot(model.name, model.robot, model.pose, origin)
        except FlatsimError as error:
            self.skipped.append(Skipped('model %s' % model.name,
                                        'a robot saved in the world that cannot run (%s); held '
                                        'still' % error))
            self._add_prims(self._place_world_model(
                model, model.pose, origin, hold='a robot saved in the world that flatsim cannot run'))
            return
        robot.saved = True
        robot.source = model

    def _slot(self, kind, cfg, robot, impl):
        mount = link_pose(robot.spec, cfg.link) * cfg.pose
        # A camera plugin's own <updateRate> can only slow the sensor down.
        rates = [r for r in (cfg.update_rate, getattr(cfg, 'plugin_update_rate', 0.0)) if r > 0]
        period = 1.0 / min(rates) if rates else 0.0
        return SensorSlot(kind, cfg, robot, impl, mount, period, next_due=self.time)

    def delete_model(self, name):
        model = self._model(name)
        self._withdraw_physics(model)
        self._forget(model)

    def _withdraw_physics(self, model):
        if model.handle is not None:
            self.physics.remove(model.handle)
        for shape in model.colliders:
            self.physics.remove_static(shape)

    def _restore_physics(self, model):
        """Puts back what _withdraw_physics took out of physics, as it was."""
        if model.handle is not None:
            self.physics.restore(model.handle)
        for shape in model.colliders:
            self.physics.restore_static(shape)

    def _forget(self, model):
        """Everything but physics of a model that leaves the world."""
        self.layout_version += 1
        for prim_id in model.prim_ids:
            self.scene.remove(prim_id)
        del self.models[model.name]
        self.origins.pop(model.name, None)
        self.wrenches.clear_model(model.name)
