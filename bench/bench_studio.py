"""What the studio (Gazebo's window as a web page) costs and how it performs.

    python bench/bench_studio.py [--seconds 10] [--rounds 2]

(a) The simulator's real-time factor running as fast as possible
    (`my_robot world.launch real_time_factor:=0`, the robot driving in circles),
    alternately with no page and with one page open in headless chromium, in one
    run; the cost is the drop with a page, in %. Target: at most 10 %.
(b) The frames per second at which that page shows model motion: rendered
    frames that showed a new pose (the page's window.studio.view.poseFrames).
    Target: at least 30.
(c) The wall time from typing `gazebo WORLD` to the page being ready (scene and
    poses shown), with no master running (gazebo starts roscore) and with one.
    The browser is started beforehand. Target: at most 2 s.
Figures only; nothing is asserted.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'tests'))
from rosproc import RosSystem, free_port  # noqa: E402
from studio_browser import launch_browser, start_studio_world, wait_ready  # noqa: E402

WORLD = os.path.join(HERE, '..', 'catkin_ws', 'src', 'my_robot', 'worlds', 'chase_house.world')
ADDRESS = re.compile(r"Gazebo's window \(flatsim studio\) is at (\S+)")


def sim_time(proxy):
    return proxy().sim_time


def real_time_factor(proxy, seconds):
    wall0, sim0 = time.monotonic(), sim_time(proxy)
    time.sleep(seconds)
    wall1, sim1 = time.monotonic(), sim_time(proxy)
    return (sim1 - sim0) / (wall1 - wall0)


def cost_and_fps(context, seconds, rounds):
    with tempfile.TemporaryDirectory() as tmp:
        with start_studio_world(tmp, ('my_robot', 'world.launch', 'gui:=false',
                                      'real_time_factor:=0')) as world:
            os.environ['ROS_MASTER_URI'] = world.ros.master_uri
            import rospy
            from gazebo_msgs.srv import GetWorldProperties
            from geometry_msgs.msg import Twist, Vector3
            rospy.init_node('bench_studio', anonymous=True, disable_signals=True)
            drive = rospy.Publisher('/cmd_vel', Twist, queue_size=1, latch=True)
            # The robot drives in circles: its pose changes at every frame.
            drive.publish(Twist(linear=Vector3(0.4, 0.0, 0.0), angular=Vector3(0.0, 0.0, 0.6)))
            proxy = rospy.ServiceProxy('/gazebo/get_world_properties', GetWorldProperties)
            time.sleep(2.0)
            without, with_page, fps = [], [], []
            for _ in range(rounds):
                without.append(real_time_factor(proxy, seconds))
                page = context.new_page()
                page.goto(world.url)
                wait_ready(page)
                time.sleep(1.0)
                frames0, wall0 = page.evaluate('window.studio.view.poseFrames'), time.monotonic()
                with_page.append(real_time_factor(proxy, seconds))
                frames1, wall1 = page.evaluate('window.studio.view.poseFrames'), time.monotonic()
                fps.append((frames1 - frames0) / (wall1 - wall0))
                page.close()
                time.sleep(1.0)
            without.append(real_time_factor(proxy, seconds))
            rospy.signal_shutdown('done')
    return without, with_page, fps


def time_to_ready(context, with_master):
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, ROS_HOME=os.path.join(tmp, 'home'), ROS_LOG_DIR=os.path.join(tmp, 'log'))
        env.pop('DISPLAY', None)
        ros = RosSystem(tmp, port=free_port(), env=env) if with_master else None
        if ros is not None:
            ros.start_master()
            env = ros.env
        else:
            env['ROS_MASTER_URI'] = 'http://localhost:%d' % free_port()
        started = time.monotonic()
        gazebo = subprocess.Popen(['gazebo', WORLD], env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, start_new_session=True)
        try:
            for line in gazebo.stdout:
                found = ADDRESS.search(line)
                if found:
                    break
            else:
                raise RuntimeError('gazebo printed no address')
            printed = time.monotonic()
            page = context.new_page()
            page.goto(found.group(1))
            wait_ready(page)
            ready = time.monotonic()
            page.close()
        finally:
            gazebo.terminate()
            gazebo.wait(30)
            if ros is not None:
                ros.stop()
    return printed - started, ready - started


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=10.0, help='length of each measuring window')
    parser.add_argument('--rounds', type=int, default=2, help='windows with a page open')
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright
    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as profile:
        context = launch_browser(playwright, profile)
        for with_master in (False, True):
            printed, ready = time_to_ready(context, with_master)
            print('(c) gazebo WORLD %s: address printed after %.2f s, page ready after %.2f s '
                  '(target at most 2 s)' % ('with a master running' if with_master
                                            else 'without a master (starts roscore)', printed, ready))
        without, with_page, fps = cost_and_fps(context, args.seconds, args.rounds)
        context.close()
    base = sum(without) / len(without)
    opened = sum(with_page) / len(with_page)
    print('(a) real-time factor, as fast as possible: no page %s, one page %s'
          % (' '.join('%.2f' % v for v in without), ' '.join('%.2f' % v for v in with_page)))
    print('    mean %.2f without, %.2f with one page: cost %.1f %% (target at most 10 %%)'
          % (base, opened, 100.0 * (1.0 - opened / base)))
    print('(b) frames per second showing model motion: %s (target at least 30)'
          % ' '.join('%.1f' % v for v in fps))


if __name__ == '__main__':
    main()
