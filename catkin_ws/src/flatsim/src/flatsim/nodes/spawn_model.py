"""spawn_model: gazebo_ros's spawn_model, talking to flatsim's gazebo/ services.

  rosrun gazebo_ros spawn_model -urdf -param robot_description -model my_robot -x 0 -y 0 -Y 0
  rosrun gazebo_ros spawn_model -sdf -file ball.sdf -model ball2 -x 1

The real tool's arguments: -urdf | -sdf; -file FILE | -param PARAM |
-database NAME | -stdin; -model NAME; -x -y -z -R -P -Y; -reference_frame;
-gazebo_namespace (/gazebo); -robot_namespace; -J JOINT POSITION (repeatable);
-unpause; -wait MODEL; -package_to_model; -b. flatsim's own: -timeout SECONDS
(60) for the simulator to come up, where the real tool waits forever.

Course-era launch files carry tokens the Kinetic spawner ignored (`_r 0`):
an unknown token is named in a warning and skipped. Exits 1 with a clear
message when the model cannot be read, the simulator refuses it or never
answers, or when flatsim cannot do what was asked (a model from Gazebo's
online database, -J on a robot without ros_control joints).
"""
import argparse
import os
import sys
import time
import xml.etree.ElementTree as ET
from urllib.parse import SplitResult, urlsplit

import rosgraph
import rospy
from gazebo_msgs.msg import ModelStates
from gazebo_msgs.srv import DeleteModel, SetModelConfiguration, SpawnModel
from std_srvs.srv import Empty

from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg, prompt_init


# rospy.wait_for_service looks every 0.3 s. A launch starts the spawner beside
# the simulator, so its model (and the robot's first camera frame) came in up to
# that much after the simulator was ready.
SERVICE_POLL_S = 0.02


class SpawnError(Exception):
    pass


class SpawnRefused(SpawnError):
    """The simulator answered that it would not spawn the model (the status says why)."""


class _ExactOptionParser(argparse.ArgumentParser):
    """Options match only in full: `-r 0` is a typo to warn about, not an ambiguous
    -reference_frame or -robot_namespace, and `-ro x` must not set -robot_namespace
    unnoticed. (Python 3.11's allow_abbrev=False still abbreviates single-dash options.)"""

    def _get_option_tuples(self, option_string):
        return []


def parse_args(argv, default_namespace='/'):
    """(arguments, unknown tokens) for gazebo_ros spawn_model's command line."""
    parser = _ExactOptionParser(prog='spawn_model', description=__doc__.split('\n')[0],
                                allow_abbrev=False)
    kind = parser.add_mutually_exclusive_group(required=True)
    kind.add_argument('-urdf', action='store_true', help='the model is URDF')
    kind.add_argument('-sdf', action='store_true', help='the model is SDF')
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument('-file', help='file holding the model XML')
    source.add_argument('-param', help='ROS parameter holding the model XML')
    source.add_argument('-database', metavar='MODEL_NAME',
                        help='a model of Gazebo\'s model database (flatsim has none)')
    source.add_argument('-stdin', action='store_true', help='read the model XML from stdin')
    parser.add_argument('-model', required=True, help='name of the model in the world')
    parser.add_argument('-reference_frame', default='',
                        help='model or link the initial pose is given in; empty or world: the world')
    parser.add_argument('-gazebo_namespace', default='/gazebo',
                        help='namespace of the simulator\'s services (default /gazebo)')
    parser.add_argument('-robot_namespace', default=default_namespace,
                        help='namespace of the model\'s plugins')
    parser.add_argument('-unpause', action='store_true', help='unpause physics after spawning')
    parser.add_argument('-wait', metavar='MODEL_NAME', help='wait for this model to exist first')
    for axis, what in [('x', 'position, m'), ('y', 'position, m'), ('z', 'position, m'),
                       ('R', 'roll, rad'), ('P', 'pitch, rad'), ('Y', 'yaw, rad')]:
        parser.add_argument('-' + axis, type=float, default=0.0, dest=axis, help=what)
    parser.add_argument('-J', dest='joints', default=[], action='append', nargs=2,
                        metavar=('JOINT_NAME', 'JOINT_POSITION'),
                        help='start the joint at this position')
    parser.add_argument('-package_to_model', action='store_true',
                        help='turn package:// mesh names into model://')
    parser.add_argument('-b', dest='bond', action='store_true',
                        help='delete the model when this program is interrupted')
    parser.add_argument('-timeout', type=float, default=60.0,
                        help='seconds to wait for the simulator (default 60)')
    args, unknown = parser.parse_known_args(argv)
    for joint in args.joints:
        try:
            joint[1] = float(joint[1])
        except ValueError:
            parser.error('argument -J: %r is not a joint position' % joint[1])
    return args, unknown


def read_model_xml(args):
    if args.file:
        if not os.path.exists(args.file):
            raise SpawnError('specified file %s does not exist' % args.file)
        if not os.path.isfile(args.file):
            raise SpawnError('specified file %s is not a file' % args.file)
        try:
            with open(args.file, encoding='utf-8') as handle:
                xml = handle.read()
        except (OSError, UnicodeDecodeError) as error:
            raise SpawnError('cannot read %s: %s' % (args.file, error)) from None
        if not xml.strip():
            raise SpawnError('file %s is empty' % args.file)
        return xml
    if args.param:
        if not rospy.has_param(args.param):
            raise SpawnError('parameter %s does not exist (is robot_description.launch included?)'
                             % rospy.resolve_name(args.param))
        xml = rospy.get_param(args.param)
        if not isinstance(xml, str) or not xml.strip():
            raise SpawnError('parameter %s is empty or not text' % rospy.resolve_name(args.param))
        return xml
    if args.database:
        raise SpawnError('-database %s: flatsim has no Gazebo model database; give the model\'s '
                         'SDF instead: -sdf -file path/to/%s/model.sdf'
                         % (args.database, args.database))
    xml = sys.stdin.read()
    if not xml.strip():
        raise SpawnError('stdin was empty')
    return xml


def prepare_xml(xml, package_to_model):
    """The XML as the real tool sends it: checked, and with model:// meshes if asked."""
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as error:
        raise SpawnError('Invalid XML: %s' % error) from None
    if package_to_model:
        for mesh in root.iterfind('.//mesh'):
            filename = mesh.get('filename')
            if filename and urlsplit(filename).scheme == 'package':
                mesh.set('filename', SplitResult('model', *urlsplit(filename)[1:]).geturl())
    return ET.tostring(root, encoding='unicode')


class Spawner:
    def __init__(self, args):
        self.args = args
        self.namespace = args.gazebo_namespace.rstrip('/')

    def service(self, name, kind):
        full = '%s/%s' % (self.namespace, name)
        if not wait_for_service(full, self.args.timeout):
            raise SpawnError('%s did not appear within %.0f s: is flatsim running?'
                             % (full, self.args.timeout))
        return rospy.ServiceProxy(full, kind)

    def wait_for_model(self, name):
        seen = []
        sub = rospy.Subscriber('%s/model_states' % self.namespace, ModelStates,
                               lambda msg: seen.append(name in msg.name))
        rospy.loginfo('Waiting for model %s before proceeding.', name)
        rate = rospy.Rate(10)
        while not rospy.is_shutdown() and not any(seen):
            rate.sleep()
        sub.unregister()

    def run(self):
        """Spawn as asked; returns the problems met after the model is in (empty if none)."""
        args = self.args
        if args.wait:
            self.wait_for_model(args.wait)
            if rospy.is_shutdown():
                return []
        xml = prepare_xml(read_model_xml(args), args.package_to_model)
        pose = rosmsg.pose_msg(Pose(args.x, args.y, args.z, args.R, args.P, args.Y))
        name = 'spawn_urdf_model' if args.urdf else 'spawn_sdf_model'
        try:
            response = self.service(name, SpawnModel)(
                model_name=args.model, model_xml=xml, robot_namespace=args.robot_namespace,
                initial_pose=pose, reference_frame=args.reference_frame)
        except rospy.ServiceException as error:
            raise SpawnError('%s/%s failed: %s' % (self.namespace, name, error)) from None
        rospy.loginfo('Spawn status: %s', response.status_message)
        if not response.success:
            raise SpawnRefused(response.status_message)
        problems = []
        if args.joints:
            # The model is in: a joint that cannot be set should not keep physics paused.
            response = self.service('set_model_configuration', SetModelConfiguration)(
                args.model, '', [joint[0] for joint in args.joints],
                [joint[1] for joint in args.joints])
            if not response.success:
                problems.append('-J: %s' % response.status_message)
        if args.unpause:
            rospy.loginfo('Unpausing physics')
            self.service('unpause_physics', Empty)()
        if args.bond:
            rospy.on_shutdown(self.delete_model)
            rospy.loginfo('Waiting for shutdown to delete model %s', args.model)
            rospy.spin()
        return problems

    def delete_model(self):
        rospy.loginfo('Deleting model %s', self.args.model)
        try:
            rospy.ServiceProxy('%s/delete_model' % self.namespace, DeleteModel)(
                model_name=self.args.model)
        except (rospy.ServiceException, rospy.ROSException) as error:
            rospy.logerr('Delete model service call failed: %s', error)


def wait_for_service(name, timeout, master=None, clock=time.monotonic, sleep=time.sleep):
    """True once the master knows a provider of service name; False after timeout wall
    seconds. Raises rospy.ROSInterruptException on shutdown, as rospy.wait_for_service."""
    resolved = rospy.resolve_name(name)
    master = master or rosgraph.Master(rospy.get_name())
    deadline = clock() + timeout
    while not rospy.is_shutdown():
        try:
            master.lookupService(resolved)
            return True
        except (rosgraph.MasterException, OSError):
            # Not registered yet (or the master is busy starting): look again.
            pass
        if clock() >= deadline:
            return False
        sleep(SERVICE_POLL_S)
    raise rospy.ROSInterruptException('rospy shutdown')


def main():
    # As the real tool: the plugins' namespace is the one this node is started in.
    args, unknown = parse_args(rospy.myargv(sys.argv)[1:], default_namespace=rospy.get_namespace())
    prompt_init.init_node('spawn_model', anonymous=True)
    if unknown:
        rospy.logwarn('spawn_model: ignoring argument(s) it does not know: %s',
                      ' '.join(unknown))
    try:
        problems = Spawner(args).run()
    except SpawnRefused:
        # The real tool's words, after the status it has logged.
        rospy.logerr('Spawn service failed. Exiting.')
        sys.exit(1)
    except (SpawnError, rospy.ServiceException, rospy.ROSException) as error:
        rospy.logerr('spawn_model: cannot spawn %s: %s', args.model, error)
        sys.exit(1)
    for problem in problems:
        rospy.logerr('spawn_model: %s: %s', args.model, problem)
    sys.exit(1 if problems else 0)
