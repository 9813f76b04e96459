"""The ros_control message stand-ins carry ROS Noetic's md5sums.

controller_manager_msgs is Noetic's ros_control's, type for type (ControllerState
with claimed_resources, SwitchController with start_asap and timeout).
control_msgs holds only JointControllerState, as Noetic's control_msgs defines it
(with i_clamp and antiwindup). The md5sums below are the ones Noetic's own
packages generate, as other client libraries' generated code records them.
A node built against the real packages talks to these only if they match.
"""
import importlib
import os

import pytest

CONTROLLER_MANAGER_MSGS = {
    'msg/ControllerState': 'aeb6b261d97793ab74099a3740245272',
    'msg/ControllerStatistics': '697780c372c8d8597a1436d0e2ad3ba8',
    'msg/ControllersStatistics': 'a154c347736773e3700d1719105df29d',
    'msg/HardwareInterfaceResources': 'f25b55cbf1d1f76e82e5ec9e83f76258',
    'srv/ListControllerTypes': 'c1d4cd11aefa9f97ba4aeb5b33987f4e',
    'srv/ListControllers': '1341feb2e63fa791f855565d0da950d8',
    'srv/LoadController': '647e5c54b8d6468952d8d31f1efe96c0',
    'srv/ReloadControllerLibraries': '40e8c411fd1797d2e2c486018f846040',
    'srv/SwitchController': 'b29a7abc673b2c54c14b54e50f8d06a5',
    'srv/UnloadController': '647e5c54b8d6468952d8d31f1efe96c0',
}
CONTROL_MSGS = {
    'msg/JointControllerState': '987ad85e4756f3aef7f1e5e7fe0595d1',
}
NOETIC_MD5SUMS = [('controller_manager_msgs', name, md5) for name, md5 in CONTROLLER_MANAGER_MSGS.items()] + \
                 [('control_msgs', name, md5) for name, md5 in CONTROL_MSGS.items()]
GAZEBO_COMPAT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_controller_manager_msgs_defines_every_noetic_type_and_nothing_else():
    package = os.path.join(GAZEBO_COMPAT, 'controller_manager_msgs')
    defined = {'%s/%s' % (kind, name[:-4]) for kind in ('msg', 'srv')
               for name in os.listdir(os.path.join(package, kind))}
    assert defined == set(CONTROLLER_MANAGER_MSGS)


@pytest.mark.parametrize('package, type_name, md5sum', NOETIC_MD5SUMS)
def test_python_md5sum_is_noetics(package, type_name, md5sum):
    kind, name = type_name.split('/')
    cls = getattr(importlib.import_module('%s.%s' % (package, kind)), name)
    assert cls._md5sum == md5sum
    assert cls._type == '%s/%s' % (package, name)
