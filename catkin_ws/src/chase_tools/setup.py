from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

# scripts: catkin_python_setup puts a relay of each into the devel space's bin,
# so `grade` is a command once devel/setup.bash (env.sh) is sourced.
setup(**generate_distutils_setup(packages=['chase_tools', 'chase_tools.grading'],
                                 package_dir={'': 'src'}, scripts=['scripts/grade']))
