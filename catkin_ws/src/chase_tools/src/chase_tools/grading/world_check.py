"""world_launches: the simulator comes up, the robot is spawned, the world has a white ball;
and what the grader reads of the spawned robot (its URDF, outline and camera)."""
import os
import time

import rosgraph
import rospy

from chase_tools import chase_graph, placement
from chase_tools.chase_graph import CAMERA_TOPIC
from chase_tools.grading.bounds import POLL_S, STATES_QUEUE
from chase_tools.grading.evidence import short
from chase_tools.grading.guard import tampered
from chase_tools.grading.rubric import NOT_JUDGED
from chase_tools.grading.scratch import READ_LIMIT
from chase_tools.procs import wait_until
from flatsim.errors import FlatsimError


def stability_advisory(spec):
    """The report's advisory line: would the robot stand, with the numbers behind it."""
    from flatsim.stability import assess
    stability, why = assess(spec)
    if stability is None:
        return 'robot stability: not judged: %s' % why
    return 'robot stability: %s' % stability.describe()


class WorldCheck:
    """The world_launches item, and the parameters and robot it reads; a part of a world's run."""

    def check_world(self):
        started = time.monotonic()
        robot_dir = os.path.join(self.spec.overlay_root, 'src', self.spec.robot_package)
        self.found.dropped_nodes = self.prepare_launch_files(robot_dir).dropped
        if self.spec.chaser_launches_world:
            # It starts the world itself: launched alone, as the submission's README runs it.
            self.bring_up_simulator(self.spec.chaser_package, 'ball_chaser.launch')
            self.found.nodes_before = self.node_names()
            self.start_chaser_launch()
        else:
            # Unchanged: a student's world.launch knows no lockstep argument (enable_lockstep).
            self.bring_up_simulator(self.spec.robot_package, 'world.launch')
            self.start_submission_launch(self.world, self.spec.robot_package, 'world.launch',
                                         self.world_log)
        self.wait_for_world(started)

    def wait_for_world(self, started):
        """world_launches, once its launch has started: the simulator, the robot, the ball."""
        from chase_tools.drawing import load_world_map
        from flatsim.loading.sdf_world import load_world
        # A bounded queue that holds every state of one read (STATES_QUEUE).
        rospy.Subscriber(chase_graph.MODEL_STATES_TOPIC, chase_graph.model_states_type(),
                         self.on_model_states, queue_size=STATES_QUEUE)
        deadline = started + self.spec.world_timeout
        came = wait_until(lambda: self.models is not None, [self.world], deadline - time.monotonic(),
                          poll_s=POLL_S)
        if not came:
            launch = 'ball_chaser.launch' if self.spec.chaser_launches_world else 'world.launch'
            if self.world.simulator_died:
                why = 'the simulator ended'
            elif not self.world.alive():
                why = '%s ended' % launch
            else:
                why = 'nothing came up within %g s' % self.spec.world_timeout
            if not self.impersonated_world():
                self.grade.set('world_launches', False,
                               'the simulator did not come up: %s; see %s'
                               % (why, self.log_label(self.world_log)),
                               self.excerpt(self.world_log))
            return False
        # The grader's own simulator runs the world it copied (bring_up_simulator).
        notes, world_file = list(self.found.world_notes), self.found.world_file
        self.found.world_map = load_world_map(world_file, notes, self.found.model_paths)
        world_names = set()
        if world_file:
            try:
                world_names = {model.name for model in load_world(world_file, self.found.model_paths).models}
            except (FlatsimError, OSError) as error:
                notes.append(str(error))
        self.found.world_file = world_file
        urdf_name = self.urdf_robot_name()
        while time.monotonic() < deadline and self.world.alive():
            names = set(self.models.name)
            spawned = sorted(names - world_names) or ([urdf_name] if urdf_name in names else [])
            if spawned:
                self.found.robot = spawned[0]
                break
            time.sleep(POLL_S)
        balls = [name for name in self.found.world_map.balls if self.models and name in self.models.name]
        self.found.ball = balls[0] if balls else None
        elapsed = time.monotonic() - started
        problems = []
        if self.found.robot is None:
            problems.append('no robot was spawned (models: %s)' % ', '.join(self.models.name))
        if self.found.ball is None:
            problems.append('the world %s has no white ball (a sphere whose colours are all 1)'
                            % os.path.basename(world_file or '(none)'))
        dropped = self.found.dropped_nodes
        if problems:
            if not self.impersonated_world():
                self.grade.set('world_launches', False, '; '.join(problems + notes),
                               self.excerpt(self.world_log))
            return False
        x, y, radius = self.found.world_map.balls[self.found.ball]
        evidence = ('the simulator came up in %.1f s with %s; robot `%s` spawned; white ball `%s` '
                    '(r %.2f m)' % (elapsed, os.path.basename(world_file), self.found.robot,
                                    self.found.ball, radius))
        if dropped:
            evidence += '; left out (no display): %s' % ', '.join(dropped)
        if self.spec.chaser_launches_world:
            evidence += '; started by ball_chaser.launch, which includes world.launch'
        self.grade.set('world_launches', True, evidence)
        self.found.spawn_pose = self.model_pose(self.found.robot)
        self.found.ball_radius = radius
        self.read_robot_geometry()
        try:
            self.judge_course_rows()
        except Exception as error:  # noqa: BLE001 - a row the grader could not judge stops no item
            self.grade.notes.append('the course rubric rows of the run could not be judged: %s: %s'
                                    % (type(error).__name__, error))
        return True

    def judge_course_rows(self):
        """The course's rubric rows that the run decides (grading/course_rubric.py): the spawned
        robot against the lesson's sample and its drive, whether it was spawned inside the
        world's walls, and whether the world launched was made with the Building Editor."""
        from chase_tools.grading import course_rubric
        from flatsim.loading.sdf_world import load_world
        found = self.found
        try:
            _name, urdf = self.robot_description()
        except (rosgraph.masterapi.Error, OSError):
            urdf = None
        if urdf is not None:
            for row, verdict in course_rubric.robot_rows(urdf, 'the spawned robot `%s`' % found.robot).items():
                self.grade.set_row(row, *verdict)
        else:
            self.grade.set_row('robot_differs_from_sample', False, NOT_JUDGED + 'no robot_description '
                               'parameter holds the URDF of the spawned robot `%s`' % found.robot, False)
        pose = found.spawn_pose
        try:
            if pose is None:
                raise FlatsimError('the spawned robot `%s` has no pose' % found.robot)
            space = placement.FreeSpace(load_world(found.world_file, found.model_paths),
                                        keep_out=[found.robot, found.ball])
            self.grade.set_row('robot_housed_in_world', *course_rubric.housed(
                pose.x, pose.y, space.enclosed(pose.x, pose.y), placement.ENCLOSURE_RAYS))
        except (FlatsimError, OSError) as error:
            self.grade.set_row('robot_housed_in_world', False, NOT_JUDGED + str(error), False)
        try:
            with open(found.world_file, errors='replace') as stream:
                text = stream.read(READ_LIMIT)
        except (OSError, TypeError) as error:
            self.grade.set_row('building_editor_world', False, NOT_JUDGED + 'the world launched could '
                               'not be read: %s' % error, False)
            return

        def model_text(name):
            for folder in found.model_paths:
                path = os.path.join(folder, name, 'model.sdf')
                if os.path.isfile(path):
                    with open(path, errors='replace') as stream:
                        return stream.read(READ_LIMIT)
            return None
        self.grade.set_row('building_editor_world', *course_rubric.building_editor(
            text, os.path.basename(found.world_file), model_text))

    def impersonated_world(self):
        """True, and world_launches not judged, when a node of the submission took the
        simulator's place while the world came up (the grader's simulator is shut down when
        another node registers under its name)."""
        tampering = self.guard.tampering()
        if tampering:
            self.grade.set('world_launches', False, tampered(tampering), self.excerpt(self.world_log))
        return bool(tampering)

    def has_param(self, name):
        try:
            return self.master.hasParam(name)
        except Exception:  # noqa: BLE001 - a master that does not answer has no such parameter
            return False

    def typed_param(self, name, kinds, what, default, notes):
        """The parameter's value if it is one of kinds, else default. A launch file's <param> is
        typed by how its value reads (value="3" is an int, "true" a bool, a <rosparam> a
        dictionary), so a parameter the grader reads may hold anything: a note then says what."""
        if not self.has_param(name):
            return default
        try:
            value = self.master.getParam(name)
        except rosgraph.masterapi.Error:
            return default
        if isinstance(value, kinds) and not isinstance(value, bool):
            return value
        note = 'the parameter %s holds %s (%s), not %s; it was not used' % (
            name, short(repr(value), 60), type(value).__name__, what)
        if note not in notes:
            notes.append(note)
        return default

    def urdf_robot_name(self):
        import xml.etree.ElementTree as ET
        text = self.typed_param('/robot_description', str, 'URDF', None, self.grade.notes)
        if text is None:
            return None
        try:
            return ET.fromstring(text).get('name')
        except ET.ParseError:
            return None

    def robot_description(self):
        """(parameter, URDF) of the spawned robot: robot_description, as the course spawns it,
        else the one parameter whose URDF names the spawned model; (None, None) if none does."""
        import xml.etree.ElementTree as ET
        names = ['/robot_description'] + sorted(set(self.master.getParamNames()) - {'/robot_description'})
        found = []
        for name in names:
            if name != '/robot_description' and not name.endswith('robot_description'):
                continue
            if not self.has_param(name):
                continue
            text = self.master.getParam(name)
            if not isinstance(text, str) or '<robot' not in text:
                continue
            try:
                robot_name = ET.fromstring(text).get('name')
            except ET.ParseError:
                continue
            found.append((name, text))
            if name == '/robot_description' or robot_name == self.found.robot:
                return name, text
        return found[0] if len(found) == 1 else (None, None)

    def read_robot_geometry(self):
        """The spawned robot's outline and camera, read here (trusted) from its URDF with
        flatsim's own loader: xacro has already run, the parameter holds URDF. Also whether
        the design would stand in Gazebo, which flatsim, keeping robots upright, cannot show:
        the rubric's "robot design is stable", advice rather than an item."""
        from flatsim.loading.urdf_robot import load_robot
        self.grade.reach = self.spec.reach
        self.found.geometry = None
        try:
            name, urdf = self.robot_description()
            if urdf is not None:
                spec = load_robot(urdf, source=name)
                if spec.cameras:
                    largest = max(spec.cameras, key=lambda camera: camera.width * camera.height)
                    self.messages.allow_frames(largest.width, largest.height)
                self.found.geometry = placement.RobotGeometry.from_spec(spec, CAMERA_TOPIC)
                self.grade.advisories.append(stability_advisory(spec))
        except (FlatsimError, rosgraph.masterapi.Error, OSError) as error:
            self.grade.notes.append('the robot description could not be read: %s' % error)
