"""Runs each package's rostest files (test/*.test) as pytest items, so one
runner reports unit tests and ROS integration tests together."""
import os
import subprocess

import pytest

ROSTEST_TIMEOUT_S = 600


def pytest_collect_file(parent, file_path):
    if file_path.suffix == '.test' and file_path.parent.name == 'test':
        return RostestFile.from_parent(parent, path=file_path)
    return None


class RostestFile(pytest.File):
    def collect(self):
        yield RostestItem.from_parent(self, name=self.path.stem)


class RostestItem(pytest.Item):
    def runtest(self):
        env = dict(os.environ)
        # rostest starts its own master; keep it on loopback like everything else.
        env.setdefault('ROS_HOSTNAME', 'localhost')
        # Not --text: in text mode rostest exits 0 even when a test case fails.
        proc = subprocess.run(
            ['rostest', str(self.path)], env=env, stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True, timeout=ROSTEST_TIMEOUT_S, check=False)
        if proc.returncode != 0 or 'RESULT: FAIL' in proc.stdout:
            raise RostestFailure(proc.stdout)

    def repr_failure(self, excinfo, style=None):
        if isinstance(excinfo.value, RostestFailure):
            return 'rostest %s failed:\n%s' % (self.path, excinfo.value.args[0][-8000:])
        return super().repr_failure(excinfo, style)

    def reportinfo(self):
        return self.path, None, 'rostest %s' % self.path.name


class RostestFailure(Exception):
    pass
