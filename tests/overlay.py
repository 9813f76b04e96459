"""Build packages in a throwaway catkin workspace on top of this one.

The course builds a student's packages in ~/catkin_ws with this workspace's
devel space sourced underneath: an overlay. Tests do the same with fixture
packages, in a temporary folder:

    ws = Overlay(tmp_path / 'ws')
    ws.add(FIXTURES / 'simple_arm')
    result = ws.build()
    assert result.returncode == 0, result.stdout
    subprocess.run(['rosrun', 'simple_arm', 'arm_mover'], env=ws.env())

build() runs catkin_make with the environment this process runs in, which
`source env.sh` has set up: the venv's python, this workspace's devel space
and env/bin/catkin_make first on PATH, exactly what a student's terminal has.
"""
import os
import shutil
import subprocess

BUILD_TIMEOUT_S = 900


class Overlay:
    def __init__(self, root):
        self.root = os.fspath(root)
        self.src = os.path.join(self.root, 'src')
        os.makedirs(self.src, exist_ok=True)
        self._env = None

    def add(self, package_dir, name=None):
        """Copy a package (or a folder of packages) into src; returns its path there."""
        target = os.path.join(self.src, name or os.path.basename(os.fspath(package_dir).rstrip('/')))
        shutil.copytree(package_dir, target, symlinks=True)
        return target

    def build(self, *args, env=None):
        """catkin_make [args] in the overlay; a CompletedProcess with stdout and stderr together."""
        self._env = None
        return subprocess.run(['catkin_make', '-C', self.root] + list(args), env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              timeout=BUILD_TIMEOUT_S, check=False)

    def env(self):
        """The environment after `source devel/setup.bash` in the overlay."""
        if self._env is None:
            setup = os.path.join(self.root, 'devel', 'setup.bash')
            dump = subprocess.run(['bash', '-c', 'source "$0" && env -0', setup],
                                  stdout=subprocess.PIPE, check=True).stdout
            self._env = dict(item.split('=', 1) for item in dump.decode().split('\0') if '=' in item)
        return dict(self._env)
