"""Spawning a URDF chain of N links: how long it takes and whether the world stops meanwhile.

    python bench/bench_spawn_chain.py [--links 250 500 1000 2000] [--no-ros]

First the core alone: reading the URDF (load_robot, outside the simulator's
lock) and putting it into the world (spawn_robot, under the lock), for fixed
and revolute chains. Then end to end: an empty world (`gazebo_ros
empty_world.launch real_time_factor:=0`) on a master of its own, and
/gazebo/spawn_urdf_model of each chain; it prints the call's wall time and
the longest wall gap between two /clock messages during the call (the
simulation loop stepping on while the model is read). Figures only.
"""
import argparse
import os
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'tests'))
from rosproc import RosSystem, free_port  # noqa: E402


def chain_urdf(links, kind):
    limit = ('<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>'
             if kind != 'fixed' else '')
    return '<robot name="chain">%s%s</robot>' % (
        ''.join('<link name="l%d"><collision><origin xyz="0.05 0 0.1"/><geometry>'
                '<box size="0.1 0.1 0.1"/></geometry></collision></link>' % i for i in range(links)),
        ''.join('<joint name="j%d" type="%s"><parent link="l%d"/><child link="l%d"/>'
                '<origin xyz="0.001 0 0"/>%s</joint>' % (i, kind, i - 1, i, limit)
                for i in range(1, links)))


def core(sizes):
    from flatsim.loading.urdf_robot import load_robot
    from flatsim.pose import Pose
    from flatsim.world.model_geometry import root_height
    from flatsim.world.sim import Simulation
    print('core: links, joint kind, read (outside the lock), spawn (under the lock)')
    for kind in ('fixed', 'revolute'):
        for links in sizes:
            xml = chain_urdf(links, kind)
            start = time.perf_counter()
            spec = load_robot(xml, name='chain')
            root_height(spec)      # as /gazebo/spawn_urdf_model does, before the lock
            read = time.perf_counter()
            Simulation().spawn_robot('chain', spec, Pose())
            done = time.perf_counter()
            print('  %5d %-8s read %.3f s  spawn %.3f s  total %.3f s'
                  % (links, kind, read - start, done - read, done - start))


def through_ros(sizes):
    with tempfile.TemporaryDirectory() as tmp:
        with RosSystem(tmp, port=free_port()) as ros:
            ros.launch('world', 'gazebo_ros', 'empty_world.launch', 'gui:=false',
                       'real_time_factor:=0')
            os.environ['ROS_MASTER_URI'] = ros.master_uri
            import rospy
            from gazebo_msgs.srv import DeleteModel, SpawnModel
            from geometry_msgs.msg import Pose
            from rosgraph_msgs.msg import Clock
            rospy.init_node('bench_spawn_chain', anonymous=True)
            rospy.wait_for_service('/gazebo/spawn_urdf_model', timeout=60)
            spawn = rospy.ServiceProxy('/gazebo/spawn_urdf_model', SpawnModel)
            delete = rospy.ServiceProxy('/gazebo/delete_model', DeleteModel)
            arrivals = []
            lock = threading.Lock()

            def on_clock(_msg):
                with lock:
                    arrivals.append(time.monotonic())
            rospy.Subscriber('/clock', Clock, on_clock, queue_size=100)
            time.sleep(1.0)
            print('through ROS: links, joint kind, spawn_urdf_model call, longest /clock gap meanwhile')
            for kind in ('fixed', 'revolute'):
                for links in sizes:
                    xml = chain_urdf(links, kind)
                    pose = Pose()
                    pose.orientation.w = 1.0
                    start = time.monotonic()
                    response = spawn(model_name='chain', model_xml=xml, initial_pose=pose,
                                     reference_frame='')
                    end = time.monotonic()
                    with lock:
                        during = [start] + [t for t in arrivals if start <= t <= end] + [end]
                    gap = max(b - a for a, b in zip(during, during[1:]))
                    print('  %5d %-8s call %.3f s  longest /clock gap %.3f s  %s'
                          % (links, kind, end - start, gap,
                             'ok' if response.success else response.status_message))
                    delete(model_name='chain')
            rospy.signal_shutdown('done')


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--links', type=int, nargs='+', default=[250, 500, 1000, 2000])
    parser.add_argument('--no-ros', action='store_true', help='the core figures only')
    args = parser.parse_args(argv)
    core(args.links)
    if not args.no_ros:
        through_ros(args.links)


if __name__ == '__main__':
    main()
