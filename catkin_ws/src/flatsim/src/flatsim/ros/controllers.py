"""gazebo_ros_control's ROS side for one robot: controller_manager services and controller topics.

Under the plugin's <robotNamespace> (ns), as gazebo_ros_control and
controller_manager advertise them:
  ns/controller_manager/{list_controllers, list_controller_types, load_controller,
      unload_controller, switch_controller, reload_controller_libraries}
  ns/<controller>/command (std_msgs/Float64) and ns/<controller>/state
      (control_msgs/JointControllerState) for joint controllers;
  ns/joint_states (sensor_msgs/JointState) for joint_state_controller;
  ns/<controller>/cmd_vel (geometry_msgs/Twist) in, ns/<controller>/odom
      (nav_msgs/Odometry) and /tf out for diff_drive_controller.
A controller's parameters are read from ns/<controller> when it is loaded.
"""

import rospy
from control_msgs.msg import JointControllerState
from controller_manager_msgs.msg import ControllerState, HardwareInterfaceResources
from controller_manager_msgs.srv import (
    ListControllers, ListControllersResponse, ListControllerTypes, ListControllerTypesResponse,
    LoadController, LoadControllerResponse, ReloadControllerLibraries,
    ReloadControllerLibrariesResponse, SwitchController, SwitchControllerResponse,
    UnloadController, UnloadControllerResponse)
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from tf2_msgs.msg import TFMessage

from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg
from flatsim.world.controllers import CONTROLLER_TYPES

BASE_CLASS = 'controller_interface::ControllerBase'


class ControlIo:
    def __init__(self, node, robot):
        self.node = node
        self.robot = robot
        self.control = robot.control
        self.namespace = '/' + self.control.manager.namespace.strip('/')
        self.topics = {}           # controller name -> [subscribers and publishers]
        self.joint_states_pub = None
        base = self.namespace.rstrip('/') + '/controller_manager/'
        self.services = [
            rospy.Service(base + 'list_controllers', ListControllers, self.on_list),
            rospy.Service(base + 'list_controller_types', ListControllerTypes, self.on_list_types),
            rospy.Service(base + 'load_controller', LoadController, self.on_load),
            rospy.Service(base + 'unload_controller', UnloadController, self.on_unload),
            rospy.Service(base + 'switch_controller', SwitchController, self.on_switch),
            rospy.Service(base + 'reload_controller_libraries', ReloadControllerLibraries,
                          self.on_reload),
        ]

    def _topic(self, controller, relative):
        if relative == '/tf':
            return relative            # diff_drive_controller publishes on the absolute /tf
        if relative.startswith('/'):
            return self.namespace.rstrip('/') + relative
        return '%s/%s/%s' % (self.namespace.rstrip('/'), controller.name, relative)

    def _log_errors(self):
        for message in self.control.manager.errors:
            rospy.logerr(message)

    def on_load(self, req):
        name = req.name
        try:
            params = rospy.get_param('%s/%s' % (self.namespace.rstrip('/'), name))
        except KeyError:
            params = None
        with self.node.lock:
            ok = self.control.manager.load(name, params)
            controller = self.control.manager.controllers.get(name)
        self._log_errors()
        if ok:
            handles = []
            twist = getattr(controller, 'command_type', None) == 'twist'
            for relative, callback in controller.commands():
                handles.append(rospy.Subscriber(self._topic(controller, relative),
                                                Twist if twist else Float64,
                                                self.on_twist if twist else self.on_command,
                                                callback_args=(controller, callback), queue_size=1))
            if twist:
                handles.append(rospy.Publisher(self._topic(controller, 'odom'), Odometry, queue_size=100))
                handles.append(rospy.Publisher('/tf', TFMessage, queue_size=100))
            elif not isinstance(controller, _state_controller_type()):
                handles.append(rospy.Publisher(self._topic(controller, 'state'),
                                               JointControllerState, queue_size=1))
            elif self.joint_states_pub is None:
                self.joint_states_pub = rospy.Publisher(self._topic(controller, '/joint_states'),
                                                        JointState, queue_size=4)
            self.topics[name] = handles
        return LoadControllerResponse(ok=ok)

    def on_unload(self, req):
        with self.node.lock:
            ok = self.control.manager.unload(req.name)
        self._log_errors()
        if ok:
            for handle in self.topics.pop(req.name, []):
                handle.unregister()
        return UnloadControllerResponse(ok=ok)

    def on_switch(self, req):
        with self.node.lock:
            ok = self.control.manager.switch(list(req.start_controllers), list(req.stop_controllers),
                                             req.strictness, self.node.sim.time)
        for message in self.control.manager.errors:
            (rospy.logwarn if message.startswith('Controller Manager:') else rospy.logerr)(message)
        return SwitchControllerResponse(ok=ok)

    def on_list(self, _req):
        with self.node.lock:
            rows = self.control.manager.listing()
        return ListControllersResponse(controller=[
            ControllerState(name=name, state=state, type=kind, claimed_resources=[
                HardwareInterfaceResources(hardware_interface=interface, resources=resources)
                for interface, resources in claims])
            for name, state, kind, claims in rows])

    def on_list_types(self, _req):
        types = sorted(CONTROLLER_TYPES)
        return ListControllerTypesResponse(types=types, base_classes=[BASE_CLASS] * len(types))

    def on_reload(self, req):
        with self.node.lock:
            names = list(self.control.manager.controllers)
            if names and not req.force_kill:
                rospy.logerr('Controller manager: Cannot reload controller libraries because there '
                             'are still %d controllers running', len(names))
                return ReloadControllerLibrariesResponse(ok=False)
            self.control.manager.switch([], names, 1, self.node.sim.time)
            for name in names:
                self.control.manager.unload(name)
        for name in names:
            for handle in self.topics.pop(name, []):
                handle.unregister()
        return ReloadControllerLibrariesResponse(ok=True)

    def on_command(self, msg, args):
        controller, callback = args
        problem = controller.untrackable(msg.data)
        if problem:
            # ros_control takes a NaN as it is; its PID then gives no effort at all.
            rospy.logwarn_throttle(5.0, '%s: command %r %s; the controller applies no effort '
                                   'until it gets one it can use' % (controller.name, msg.data, problem))
        with self.node.lock:
            callback(msg.data)

    def on_twist(self, msg, args):
        controller, callback = args
        with self.node.lock:
            callback(msg.linear.x, msg.angular.z, self.node.sim.time)
            self.node.record_command(self.robot, msg)

    def publish(self):
        """Send what the controllers produced in the last steps."""
        for controller, topic, fields in self.control.outbox():
            if topic in ('odom', '/tf'):
                self._publish_odometry(controller, topic, fields)
                continue
            stamp = rospy.Time.from_sec(fields.pop('stamp'))
            if topic == '/joint_states':
                if self.joint_states_pub is not None:
                    msg = JointState(**fields)
                    msg.header.stamp = stamp
                    self.joint_states_pub.publish(msg)
                continue
            handles = self.topics.get(controller.name, [])
            publishers = [h for h in handles if isinstance(h, rospy.Publisher)]
            if publishers and publishers[0].get_num_connections():
                msg = JointControllerState(**fields)
                msg.header.stamp = stamp
                publishers[0].publish(msg)

    def _publish_odometry(self, controller, topic, fields):
        publishers = [h for h in self.topics.get(controller.name, []) if isinstance(h, rospy.Publisher)]
        wanted = Odometry if topic == 'odom' else TFMessage
        publishers = [p for p in publishers if p.data_class is wanted]
        if not publishers:
            return
        pose = Pose(fields['x'], fields['y'], 0.0, 0.0, 0.0, fields['yaw'])
        if topic == '/tf':
            publishers[0].publish(TFMessage(transforms=[rosmsg.transform_msg(
                fields['stamp'], fields['frame_id'], fields['child_frame_id'], pose)]))
            return
        msg = rosmsg.odometry_msg(fields['stamp'], fields['frame_id'], fields['child_frame_id'], pose,
                                  (fields['linear'], 0.0, fields['angular']))
        msg.pose.covariance = [0.0] * 36
        msg.twist.covariance = [0.0] * 36
        for i in range(6):
            msg.pose.covariance[i * 7] = fields['pose_covariance'][i]
            msg.twist.covariance[i * 7] = fields['twist_covariance'][i]
        publishers[0].publish(msg)

    def close(self):
        for service in self.services:
            service.shutdown()
        for handles in self.topics.values():
            for handle in handles:
                handle.unregister()
        if self.joint_states_pub is not None:
            self.joint_states_pub.unregister()


def _state_controller_type():
    return CONTROLLER_TYPES['joint_state_controller/JointStateController']
