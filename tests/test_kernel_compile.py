"""The world runs while the sensor kernels compile.

A user who cannot write numba's cache beside flatsim's sources (the workspace
built by another user, or a cache that is cold) compiles the kernels into a
cache of their own at the simulator's first start, which takes seconds. Sim
time must run meanwhile: a world without a camera needs none of them, and a
studio showing a frozen world looks broken.
"""
import os
import re
import signal

from rosproc import free_port, run_forked, wait_until
from studio_browser import _call_service
from test_studio_commands import ADDRESS, Command, environment

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WORLD = os.path.join(TOP, 'catkin_ws', 'src', 'my_robot', 'worlds', 'chase_house.world')
COMPILED = 'flatsim: compiled the sensor kernels'


def sim_time(master_uri):
    return run_forked(_call_service, master_uri, '/gazebo/get_world_properties',
                      'gazebo_msgs/GetWorldProperties', {})['sim_time']


def test_sim_time_runs_while_the_kernels_compile_into_an_empty_cache(tmp_path):
    master_uri = 'http://localhost:%d' % free_port()
    # An empty cache of its own: numba compiles every kernel, as for a user with none.
    env = environment(tmp_path, master_uri, NUMBA_CACHE_DIR=str(tmp_path / 'numba'))
    gazebo = Command(['gazebo', WORLD], env)
    try:
        gazebo.wait_for(ADDRESS.pattern, timeout=120.0)
        def first():
            if COMPILED in gazebo.output:
                return 'the kernels compiled first'
            return sim_time(master_uri) > 0.5 and 'sim time ran first'
        assert wait_until(first, 120.0) == 'sim time ran first', (
            'sim time waited for the kernels to compile:\n%s' % gazebo.output[-3000:])
        # They did compile, into that cache, once the world was running.
        gazebo.wait_for(re.escape(COMPILED), timeout=300.0)
        assert os.listdir(tmp_path / 'numba')
    finally:
        assert gazebo.stop(signal.SIGINT) == 0, gazebo.output[-3000:]
