from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(
    packages=['flatsim', 'flatsim.loading', 'flatsim.world', 'flatsim.sensors', 'flatsim.ros',
              'flatsim.nodes', 'flatsim.studio'],
    package_dir={'': 'src'}))
