"""A spawn that arrives as soon as Gazebo's services are registered waits until the robots
saved in the world file have their topics and services. Were it to go first, both it and
the loading would register the spawned robot's, and a robot under ros_control would end
flatsim with "service [.../controller_manager/list_controllers] already registered"."""
import multiprocessing
import os
import threading
import traceback

import rospy

from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.ros import node as node_module

HERE = os.path.dirname(os.path.abspath(__file__))
SIMPLE_ARM_XACRO = os.path.join(HERE, '..', '..', 'simple_arm', 'urdf', 'simple_arm.urdf.xacro')
SPAWN_HEAD_START_S = 0.5


def _load_while_a_spawn_arrives(results):
    try:
        # No master: every parameter its default, and none set.
        rospy.get_param = lambda _name, default=None: default
        rospy.set_param = lambda _name, _value: None
        # As init_node leaves it, for ~names, but with nothing registered anywhere.
        rospy.names._set_caller_id('/flatsim')
        rospy.core.set_initialized(True)
        spec = load_robot(expand_xacro(SIMPLE_ARM_XACRO), name='simple_arm')
        errors = []

        def spawn(node):
            try:
                with node.lock:     # as GazeboApi's spawn services place a model
                    node.add_model('simple_arm', spec, Pose())
            except Exception:  # noqa: BLE001 - the race under test may fail anywhere; its traceback is the evidence
                errors.append(traceback.format_exc())

        class ServicesThatAnswerAtOnce:
            """Gazebo's API, with a spawn request already waiting when its services come up."""

            def __init__(self, node, _world):
                self.spawner = threading.Thread(target=spawn, args=(node,))
                self.spawner.start()
                self.spawner.join(SPAWN_HEAD_START_S)

        node_module.GazeboApi = ServicesThatAnswerAtOnce
        node = node_module.FlatsimNode.__new__(node_module.FlatsimNode)
        node.lock = threading.RLock()
        node.seed, node.real_time_factor, node.world_name = 0, 1.0, ''
        node._load('')
        node.gazebo.spawner.join(10.0)
        results.put((errors, sorted(node.robot_io), [robot.name for robot in node.sim.robots()]))
    except Exception:  # noqa: BLE001 - the race under test may fail anywhere; its traceback is the evidence
        results.put(([traceback.format_exc()], None, None))


def test_a_spawn_while_the_world_loads_waits_for_the_saved_robots():
    # In a child: the rospy services it registers stay out of this process.
    results = multiprocessing.get_context('fork').Queue()
    child = multiprocessing.get_context('fork').Process(target=_load_while_a_spawn_arrives, args=(results,))
    child.start()
    errors, robot_io, robots = results.get(timeout=60)
    child.join(10)
    assert errors == []
    assert robot_io == ['simple_arm'] and robots == ['simple_arm']
