"""controller_manager/spawner: load and start controllers, and take them down on exit.

Arguments and messages are those of ros_control's spawner (noetic):
  spawner [--stopped] [--wait-for TOPIC] [--namespace NS] [--timeout T]
          [--no-timeout] [--shutdown-timeout T] controller [controller ...]
Each controller is a name whose parameters (type, joint, pid, ...) are on the
parameter server under the controller manager's namespace, or a YAML file of
such controllers, which is loaded onto the parameter server first. The
services are resolved relative to the node's namespace (or --namespace), so
`<node pkg="controller_manager" type="spawner" ns="/simple_arm" .../>` talks to
/simple_arm/controller_manager/*.
"""
import argparse
import os
import time

import rosparam
import rospy
import yaml
from controller_manager_msgs.srv import (LoadController, SwitchController, SwitchControllerRequest,
                                         UnloadController)
from std_msgs.msg import Bool


def parse_args(argv):
    parser = argparse.ArgumentParser(description='Controller spawner')
    parser.add_argument('--stopped', action='store_true',
                        help='loads controllers, but does not start them')
    parser.add_argument('--wait-for', metavar='topic',
                        help='does not load or start controllers until it hears "True" on a topic (Bool)')
    parser.add_argument('--namespace', metavar='ns', help='namespace of the controller_manager services')
    parser.add_argument('--timeout', metavar='T', type=float, default=30,
                        help='how long to wait for controller_manager services when starting up [s] '
                             '(default: 30). <=0 waits indefinitely.')
    parser.add_argument('--no-timeout', action='store_true',
                        help='wait for controller_manager services indefinitely (same as `--timeout 0`)')
    parser.add_argument('--shutdown-timeout', help='DEPRECATED: this argument has no effect.')
    parser.add_argument('controllers', metavar='controller', nargs='+', help='controllers to load')
    return parser.parse_args(argv)


def controller_names(arguments):
    """Controller names, loading each YAML file argument onto the parameter server."""
    names = []
    for argument in arguments:
        if os.path.isfile(argument):
            names.extend(load_controller_file(argument))
        else:
            if argument.endswith(('.yaml', '.yml')):
                rospy.logerr('Controller Spawner: %s looks like a YAML file of controllers, but there '
                             'is no such file; trying it as a controller name', argument)
            names.append(argument)
    return names


def load_controller_file(path):
    """Put a YAML file's parameters on the parameter server; the names of its top-level entries.

    A file that cannot be read, is not YAML or is not a mapping is named with the
    reason, and gives no controllers; the spawner goes on with its other arguments.
    """
    try:
        with open(path, encoding='utf-8') as stream:
            params = yaml.safe_load(stream)
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        rospy.logerr('Controller Spawner: cannot load %s: %s', path, error)
        return []
    if not isinstance(params, dict):
        rospy.logerr('Controller Spawner: %s holds no controllers (a YAML mapping of controller names '
                     'to their parameters is expected)', path)
        return []
    rosparam.set_param_raw('', params)  # what `rosparam.set_param('', text)` does, parsed once
    return list(params)


class Spawner:
    def __init__(self, args):
        self.args = args
        prefix = args.namespace or ''
        if prefix and not prefix.endswith('/'):
            prefix += '/'
        self.load_name = prefix + 'controller_manager/load_controller'
        self.switch_name = prefix + 'controller_manager/switch_controller'
        self.unload_name = prefix + 'controller_manager/unload_controller'
        self.loaded = []

    def wait_for_services(self):
        timeout = None if self.args.no_timeout or self.args.timeout <= 0 else self.args.timeout
        try:
            for name in (self.load_name, self.switch_name, self.unload_name):
                rospy.loginfo('Controller Spawner: Waiting for service ' + name)
                rospy.wait_for_service(name, timeout=timeout)
        except rospy.exceptions.ROSException:
            rospy.logwarn("Controller Spawner couldn't find the expected controller_manager ROS interface.")
            return False
        return True

    def wait_for_topic(self):
        heard = []
        rospy.Subscriber(self.args.wait_for, Bool, heard.append)
        started, warned = time.time(), False
        while not (heard and heard[-1].data):
            if rospy.is_shutdown():
                return False
            if not heard and not warned and time.time() - started > self.args.timeout:
                warned = True
                rospy.logwarn('Controller Spawner hasn\'t heard anything from its "wait for" topic (%s)'
                              % self.args.wait_for)
            time.sleep(0.01)
        return True

    def run(self):
        if self.args.shutdown_timeout is not None:
            rospy.logwarn('DEPRECATION warning: --shutdown-timeout has no effect.')
        if not self.wait_for_services():
            return
        if self.args.wait_for and not self.wait_for_topic():
            return
        rospy.on_shutdown(self.shutdown)
        load = rospy.ServiceProxy(self.load_name, LoadController)
        for name in controller_names(self.args.controllers):
            rospy.loginfo('Loading controller: ' + name)
            if load(name).ok:
                self.loaded.append(name)
            else:
                time.sleep(1)  # as upstream: let the controller manager's error get out first
                rospy.logerr('Failed to load %s' % name)
        rospy.loginfo('Controller Spawner: Loaded controllers: %s' % ', '.join(self.loaded))
        if rospy.is_shutdown():
            return
        if not self.args.stopped:
            switch = rospy.ServiceProxy(self.switch_name, SwitchController)
            if switch(self.loaded, [], SwitchControllerRequest.STRICT, False, 0.0).ok:
                rospy.loginfo('Started controllers: %s' % ', '.join(self.loaded))
            else:
                rospy.logerr('Failed to start controllers: %s' % ', '.join(self.loaded))
        rospy.spin()

    def shutdown(self):
        rospy.loginfo('Shutting down spawner. Stopping and unloading controllers...')
        try:
            switch = rospy.ServiceProxy(self.switch_name, SwitchController)
            unload = rospy.ServiceProxy(self.unload_name, UnloadController)
            rospy.loginfo('Stopping all controllers...')
            switch([], self.loaded, SwitchControllerRequest.STRICT, False, 0.0)
            rospy.loginfo('Unloading all loaded controllers...')
            for name in reversed(self.loaded):
                rospy.loginfo('Trying to unload %s' % name)
                unload(name)
                rospy.loginfo('Succeeded in unloading %s' % name)
        except (rospy.ServiceException, rospy.exceptions.ROSException) as error:
            rospy.logwarn('Controller Spawner error while taking down controllers: %s' % error)


def main():
    args = parse_args(rospy.myargv()[1:])
    rospy.init_node('spawner', anonymous=True)
    Spawner(args).run()
