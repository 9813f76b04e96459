"""gazebo_ros_control's update loop for one robot: controllers, hardware, joint motion.

Each physics step, as gazebo_ros_control's Update() does: when a control
period has passed, the controller manager updates every running controller
with the joint state; then the commands go through the hardware's limit
handles into the joints, which move for one step.
"""
import numpy as np

from flatsim.pose import Pose
from flatsim.world.articulation import Articulation
from flatsim.world.controllers import ControllerManager, RobotHW


class RobotControl:
    def __init__(self, spec, step_size):
        config = spec.ros_control
        self.spec = spec
        self.articulation = Articulation(spec)
        self.hw = RobotHW(self.articulation, config.transmissions)
        self.hw.spec = spec    # diff_drive_controller looks its wheels up in the robot description
        self.manager = ControllerManager(self.hw, config.robot_namespace)
        self.control_period = config.control_period or step_size
        self.last_update = None
        # Which body each link rides on, and where on it: fixed by the URDF, asked per frame.
        self._link_offsets = {}

    def step(self, time, dt):
        if self.last_update is None:
            self.last_update = time - self.control_period
        if time - self.last_update >= self.control_period - 1e-9:
            self.manager.update(time, time - self.last_update)
            self.last_update = time
        self.articulation.step(dt, self.hw.write(dt))

    def reset(self):
        """Joints back to zero at rest, and every running controller started afresh."""
        articulation = self.articulation
        articulation.position[:] = 0.0
        articulation.velocity[:] = 0.0
        for joint in self.hw.joints.values():
            joint.previous_command = float('nan')
        self.last_update = None

    def link_pose(self, link):
        """Pose of a link in the robot's root frame at the present joint positions."""
        found = self._link_offsets.get(link)
        if found is None:
            found = self._link_offsets[link] = self.articulation.link_offset(self.spec, link)
        index, offset = found
        if index < 0:
            return offset
        frame = self.articulation.body_frames()[index] @ offset.matrix()
        return Pose.from_matrix(frame)

    def outbox(self):
        """(controller, topic, fields) the controllers want published; emptied as it is read."""
        items = []
        for controller in self.manager.controllers.values():
            items.extend((controller, topic, fields) for topic, fields in controller.outbox)
            controller.outbox.clear()
        return items

    def joint_positions(self):
        return dict(zip(self.articulation.joints, np.asarray(self.articulation.position).tolist()))
