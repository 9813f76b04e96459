"""The xacro stand-in script: pip's xacro's output and errors, without loading roslaunch's launcher."""
import os
import subprocess
import sys

import pytest

PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(PACKAGE, 'xacro')
TOP = os.path.abspath(os.path.join(PACKAGE, '..', '..', '..', '..'))
ROBOT = os.path.join(TOP, 'catkin_ws', 'src', 'my_robot', 'urdf', 'my_robot.xacro')


def run(argv, *python_options):
    return subprocess.run([sys.executable, *python_options] + argv, capture_output=True,
                          text=True, timeout=60)


def pip_xacro(argv):
    return run(['-c', 'import sys, xacro; sys.argv[0] = "xacro"; xacro.main()'] + argv)


@pytest.mark.parametrize('mappings', [[], ['drive:=skid']])
def test_same_urdf_as_pips_xacro(mappings):
    ours = run([SCRIPT, ROBOT] + mappings)
    assert ours.returncode == 0, ours.stderr
    assert ours.stdout == pip_xacro([ROBOT] + mappings).stdout
    assert '<robot name="my_robot"' in ours.stdout


def test_substitution_errors_as_pips_xacro(tmp_path):
    robot = tmp_path / 'bad.xacro'
    robot.write_text('<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                     '<link name="$(find no_such_package)"/></robot>')
    ours = run([SCRIPT, str(robot)])
    assert ours.returncode == 2
    assert 'resource not found: no_such_package' in ours.stderr
    reference = pip_xacro([str(robot)])
    assert (ours.returncode, ours.stderr) == (reference.returncode, reference.stderr)


def test_args_env_and_eval_substitutions(tmp_path):
    robot = tmp_path / 'args.xacro'
    robot.write_text('<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                     '<xacro:arg name="side" default="left"/>'
                     '<link name="$(arg side)_$(env XACRO_TEST_WORD)_$(eval 1 + 2)"/></robot>')
    ours = subprocess.run([sys.executable, SCRIPT, str(robot), 'side:=right'], capture_output=True,
                          text=True, timeout=60, env=dict(os.environ, XACRO_TEST_WORD='word'))
    assert '<link name="right_word_3"/>' in ours.stdout, ours.stderr


def test_does_not_load_the_launcher():
    """roslaunch/__init__.py would import roslaunch.launch (and setuptools, numpy) first."""
    ours = run([SCRIPT, ROBOT], '-X', 'importtime')
    assert ours.returncode == 0
    imported = {line.rsplit('|', 1)[-1].strip() for line in ours.stderr.splitlines()}
    assert 'roslaunch.substitution_args' in imported
    assert 'roslaunch.launch' not in imported
    assert 'setuptools' not in imported


def test_xacro_on_the_environments_path_is_this_script():
    """roslaunch runs `command="xacro ..."` from PATH, where env.sh puts env/bin first."""
    assert os.path.realpath(os.path.join(TOP, 'env', 'bin', 'xacro')) == os.path.realpath(SCRIPT)
