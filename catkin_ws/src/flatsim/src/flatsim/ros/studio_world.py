"""The studio (Gazebo's window as a web page) on the simulator node.

NodeWorld is the studio's WorldAccess over the running node: it reads the
world under the node's lock, and every change goes through the same code as
gazebo_ros's services (flatsim.ros.gazebo_api), so /gazebo/get_model_state,
the sensors and the robot's nodes see an edit at once. start_studio() reads
the node's ~studio parameters, starts the server, logs the page's address
without its token and writes it, token and all, where gzclient looks (flatsim.studio.address).
When the master is not up yet (`gazebo WORLD` starts roscore beside the
simulator), the node starts it before it registers, with the ~studio
parameters of its command line, so that a browser loads the page while the
master and the world load; the node attaches itself when it exists and opens
the studio (RunningStudio.open) once the world is loaded. On a running
master, the node starts it before it loads the world with ~studio_first (as
the gazebo and gzserver commands run it), and otherwise (a launch file)
beside the stepping loop once the world steps, so that the robot's first
sensor frames do not wait for the web server's imports.
"""
import copy
import logging
import os

import rosgraph
import rospkg
import rospy
from gazebo_msgs.msg import ModelState
from gazebo_msgs.srv import DeleteModelRequest, SetModelStateRequest
from std_srvs.srv import EmptyRequest

from flatsim.authoring.world_writer import world_sdf
from flatsim.errors import FlatsimError
from flatsim.ros import messages as rosmsg
from flatsim.studio import address, editors
from flatsim.studio.chase import CommandLog
from flatsim.studio.hub import Hub
from flatsim.studio.protocol import finite_float
from flatsim.studio.scaling import rescale
from flatsim.studio.server import HOST, StudioError, StudioServer, listen_address, port_number
from flatsim.studio.world import (Outcome, SnapshotTaker, WorldAccess, describe_scene, find_sensor,
                                  gui_camera_pose, keep_model, model_parts, model_to_insert,
                                  placed_again, scan_of, skipped_items)

# Poses per second of wall time to open pages: 40 is smooth motion at a small cost.
DEFAULT_RATE, MIN_RATE, MAX_RATE = 40.0, 1.0, 240.0


class NodeWorld(WorldAccess):
    def __init__(self, node, world_name=''):
        self.node = node              # None until the node attaches (no page is greeted before)
        self.world_name = world_name
        self.snapshot_taker = SnapshotTaker()
        self.service_watch = None     # the chase view's calls to /ball_chaser/command_robot

    def read(self, read):
        return self.node.read_between_steps(read)

    def snapshot(self):
        return self.read(lambda: self.snapshot_taker.take(self.node.sim))

    def scene(self):
        def read():
            self.node.sim.sync_moving_prims()
            return describe_scene(self.node.sim, self.world_name,
                                  gui_camera_pose(getattr(self.node, 'world', None)))
        return self.read(read)

    def skipped(self):
        return self.read(lambda: skipped_items(self.node.sim))

    def set_model_pose(self, name, pose):
        request = SetModelStateRequest(model_state=ModelState(
            model_name=name, pose=rosmsg.pose_msg(pose), reference_frame='world'))
        response = self.node.gazebo.set_model_state(request)
        return Outcome(response.success, response.status_message)

    def delete_model(self, name):
        response = self.node.gazebo.delete_model(DeleteModelRequest(model_name=name))
        return Outcome(response.success, response.status_message)

    def copy_model(self, source, name, pose):
        response = self.node.gazebo.spawn_copy(source, name, pose)
        return Outcome(response.success, response.status_message)

    def scale_model(self, name, scale):
        try:
            with self.node.lock:
                rescale(self.node.sim, name, scale)
        except FlatsimError as error:
            return Outcome(False, str(error))
        # A sphere scaled past a ball's size is a ball no more.
        self.node.publish_ball_names()
        return Outcome(True, 'scaled %s' % name)

    def keep_model(self, name):
        return keep_model(self.read(lambda: model_parts(self.node.sim, name)))

    def restore_model(self, kept):
        response = self.node.gazebo.restore_model(kept.name, kept.robot, copy.deepcopy(kept.loaded),
                                                  kept.pose, kept.origin)
        if response.success:
            with self.node.lock:
                model = self.node.sim.models.get(kept.name)
                if model is not None:
                    placed_again(model, kept)
        return Outcome(response.success, response.status_message)

    def insert_model(self, name, sdf, position=None, path=None):
        try:
            # Read outside the lock: a big model takes a while, and the world steps on meanwhile.
            model, pose, origin = model_to_insert(name, sdf, position, path)
        except FlatsimError as error:
            return Outcome(False, 'SpawnModel: Failure - %s' % error)
        response = self.node.gazebo.insert_model(name, model, pose, origin)
        return Outcome(response.success, response.status_message)

    def world_sdf(self):
        return self.read(lambda: world_sdf(self.node.sim, self.node.world))

    def pause(self):
        self.node.gazebo.pause_physics(EmptyRequest())
        return Outcome(True, 'paused')

    def play(self):
        self.node.gazebo.unpause_physics(EmptyRequest())
        return Outcome(True, 'running')

    def step(self, count):
        """count: 1 to MAX_STEPS (flatsim.studio.protocol), as the step command checks it."""
        if not self.node.step_paused(count):
            return Outcome(False, 'step works while paused; press pause first')
        return Outcome(True, 'stepped %d' % count)

    def reset_model_poses(self):
        self.node.gazebo.reset_world(EmptyRequest())
        return Outcome(True, 'model poses reset')

    def reset_world(self):
        self.node.gazebo.reset_simulation(EmptyRequest())
        return Outcome(True, 'world reset')

    def camera_image(self, sensor):
        def read():
            slot = find_sensor(self.node.sim, sensor, 'camera')
            if slot is None:
                return None
            return self.node.sim.time, self.node.sim.sense(slot), slot.impl.encoding()
        found = self.read(read)
        if found is None:
            return None
        now, pixels, encoding = found
        return now, pixels[..., ::-1] if encoding == 'bgr8' else pixels

    def want_scans(self, wanted):
        self.node.studio_scans = wanted

    def want_commands(self, wanted):
        # Read by the /cmd_vel callback: None records nothing.
        self.node.command_log = CommandLog() if wanted else None
        if wanted:
            self._service_watch().open()
        elif self.service_watch is not None:
            self.service_watch.close()

    def _service_watch(self):
        if self.service_watch is None:
            # Imported here: a simulator whose chase view never opens never loads it.
            from flatsim.ros.service_watch import RosGraph
            from flatsim.studio.service_watch import ServiceWatch
            self.service_watch = ServiceWatch(RosGraph(), lambda: self.node.sim.time)
            # Before rospy stops answering calls: the serving node's levels go back.
            rospy.on_shutdown(self.service_watch.shutdown)
        return self.service_watch

    def drive_commands(self, model, now):
        log = self.node.command_log
        return [] if log is None else log.recent(model, now)

    def service_calls(self, now):
        watch = self.service_watch
        return None if watch is None else watch.calls(now)

    def scans(self):
        def read():
            sim, found = self.node.sim, []
            for robot in sim.robots():
                for slot in robot.sensors:
                    scan = self.node.last_scans.get(id(slot))
                    if scan is not None:
                        ranges, angles, (x, y, yaw) = scan
                        found.append((slot, ranges, angles, (x, y, sim.sensor_pose(slot).z, yaw)))
            return found
        return [scan_of(*item) for item in self.read(read)]


def client_dirs():
    """(the page's folder, three.js's folder) in the flatsim package."""
    web = os.path.join(rospkg.RosPack().get_path('flatsim'), 'studio_web')
    return os.path.join(web, 'client'), os.path.join(web, 'node_modules', 'three')


class RunningStudio:
    """The studio's server and the address it wrote."""

    def __init__(self, server, path, url):
        self.server = server
        self.path = path
        self.url = url

    def attach(self, node):
        """The node the studio shows, once it exists (and rospy logs)."""
        self.server.hub.world.node = node
        # Without the token: rospy's log goes to /rosout, which anyone on the graph can read.
        rospy.loginfo('flatsim: the studio (Gazebo\'s window) is at %s ; gzclient opens it with '
                      'its token, from %s', address.without_token(self.url), self.path)

    def open(self):
        """Show pages the world: call once the node has loaded it."""
        self.server.open_world()

    def stop(self):
        address.remove_address(self.path, self.url)
        self.server.stop()


def start_studio(world_name, params=None):
    """Start the studio if ~studio (default true), pages waiting until the node attaches and
    opens it; returns the RunningStudio or None.

    With ~studio_save_over_world, File > Save World writes over world_name, and files may be
    saved in its folder (flatsim.studio.editors).

    params: the node's private parameters as a dict (its command line's, before the master
    answers); by default the parameter server's. A studio that cannot start is reported
    and the simulator runs on without it.
    """
    def param(name, default):
        if params is None:
            return rospy.get_param('~' + name, default)
        return params.get(name, default)

    if not param('studio', True):
        return None
    try:
        port = port_number(param('studio_port', 0))
        host = listen_address(param('studio_listen', HOST))
    except StudioError as error:
        rospy.logerr('flatsim: no studio (Gazebo\'s window): %s', error)
        return None
    given_rate = param('studio_rate', DEFAULT_RATE)
    rate = finite_float(given_rate)
    if isinstance(given_rate, str):
        try:
            rate = finite_float(float(given_rate))
        except ValueError:
            rate = None
    if rate is None or not MIN_RATE <= rate <= MAX_RATE:
        rospy.logwarn('flatsim: ~studio_rate %.40r is not a number of Hz between %g and %g; '
                      'using %g Hz', given_rate, MIN_RATE, MAX_RATE, DEFAULT_RATE)
        rate = DEFAULT_RATE
    hub = Hub(NodeWorld(None, os.path.basename(world_name) if world_name else ''),
              log=logging.getLogger('rosout'), stream_rate=rate)
    save_over_world = bool(param('studio_save_over_world', False))
    editors.install(hub, world_name if save_over_world else '')
    client_dir, three_dir = client_dirs()
    server = StudioServer(hub, client_dir, three_dir, port=port, host=host)
    try:
        url = server.start(world_open=False)
    except StudioError as error:
        rospy.logerr('flatsim: no studio (Gazebo\'s window): %s', error)
        return None
    master_uri = rosgraph.get_master_uri()
    path = address.address_path(master_uri)
    try:
        address.write_address(path, url, master_uri)
    except OSError as error:
        rospy.logwarn('flatsim: cannot write the studio\'s address to %s: %s', path, error)
    studio = RunningStudio(server, path, url)
    rospy.on_shutdown(studio.stop)
    return studio
