"""gzserver: the simulator (flatsim) without a window; see flatsim.nodes.gazebo.

  gzserver [-u] [--verbose] [--listen ADDRESS[:PORT]] [WORLD]    # also rosrun gazebo_ros gzserver

The studio is served all the same: gzclient opens it later.
"""
from flatsim.nodes.gazebo import run


def main():
    run('gzserver', gui=False)
