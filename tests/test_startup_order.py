"""What the simulator starts first on a running master: for a launch file, the world (the
studio's web server waits until the world steps, so that the robot's first sensor frames do
not wait for its imports); for `gazebo WORLD`, whose user waits for the page, the studio. Read
from the simulator's own lines, in the order it wrote them."""
import os
import re
import subprocess

from rosproc import RosSystem, wait_until

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WORLD = 'catkin_ws/src/my_robot/worlds/chase_house.world'
STUDIO_LINE = "flatsim: the studio (Gazebo's window) is at"
WORLD_LINE = 'flatsim: world '
# What gazebo itself prints once the page answers.
ADDRESS = re.compile(r"Gazebo's window \(flatsim studio\) is at http")


def line_order(text, *needles):
    return [text.index(needle) for needle in needles]


def test_a_launch_steps_its_world_before_the_studio_starts_and_spawns_its_robot(tmp_path):
    """The spawner is a process of its own, which calls the simulator once it serves: whether
    its line comes before the studio's or after is a race between two processes, not a promise."""
    with RosSystem(tmp_path) as ros:
        ros.launch('world', 'my_robot', 'world.launch', 'gui:=false')
        spawned = 'Spawn status: SpawnModel: Success'
        assert wait_until(lambda: STUDIO_LINE in ros.log_tail('world', 200000)
                          and spawned in ros.log_tail('world', 200000), 60.0), ros.log_tail('world')
        log = ros.log_tail('world', 200000)
        world, studio = line_order(log, WORLD_LINE, STUDIO_LINE)
        assert world < studio, log
        assert 'Traceback' not in log


def test_gazebo_world_on_a_running_master_starts_the_studio_first(tmp_path):
    with RosSystem(tmp_path) as ros:
        env = dict(ros.env, ROS_HOME=str(tmp_path / 'ros_home'))
        env.pop('DISPLAY', None)
        gazebo = subprocess.Popen(['gazebo', WORLD], env=env, cwd=TOP, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, start_new_session=True)
        lines = []
        try:
            for line in gazebo.stdout:
                lines.append(line)
                if WORLD_LINE in ''.join(lines) and ADDRESS.search(''.join(lines)):
                    break
        finally:
            gazebo.terminate()
            rest, _ = gazebo.communicate(timeout=30)
        output = ''.join(lines) + rest
        assert STUDIO_LINE in output and WORLD_LINE in output, output
        studio, world = line_order(output, STUDIO_LINE, WORLD_LINE)
        assert studio < world, output
