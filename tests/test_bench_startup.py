"""bench/bench_startup.py, as docs/simulator.md shows it: the course's world to its first
camera image, timed from a listener that needs no master; and its bad arguments."""
import os
import re
import subprocess
import sys

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BENCH = os.path.join(TOP, 'bench', 'bench_startup.py')
# An 800x800 rgb8 sensor_msgs/Image: its header (frame "camera"), the sizes and encoding, the pixels.
COURSE_IMAGE = re.compile(r'first image after \d+\.\d+ s \((19200\d\d) bytes\)')


def bench(*args, timeout=180):
    return subprocess.run([sys.executable, BENCH] + list(args), capture_output=True, text=True,
                          timeout=timeout, cwd=TOP)


def test_one_run_reads_the_course_camera_image_and_names_every_milestone():
    result = bench('--runs', '1')
    assert result.returncode == 0, result.stdout + result.stderr
    assert COURSE_IMAGE.search(result.stdout), result.stdout
    for milestone in ('master answers', 'flatsim registered', 'spawn service up',
                      'camera publisher registered', 'first image'):
        assert re.search(r'^  %s +\d+\.\d{3}' % milestone, result.stdout, re.M), result.stdout
    assert re.search(r'^first image, this shell: median \d+\.\d{3} s', result.stdout, re.M)


def test_bad_arguments_get_a_clear_error():
    result = bench('--runs', '0', timeout=60)
    assert result.returncode == 2 and '--runs must be at least 1' in result.stderr
    result = bench('--checkouts', '/nonexistent/checkout', timeout=60)
    assert result.returncode == 2 and 'no env.sh in /nonexistent/checkout' in result.stderr


def test_a_command_that_ends_or_cannot_run_is_reported_with_its_output():
    result = bench('--runs', '1', '--command', 'roslaunch my_robot no_such.launch', timeout=120)
    assert result.returncode == 1 and 'Traceback' not in result.stderr
    assert 'roslaunch my_robot no_such.launch ended with status' in result.stderr
    assert 'no_such.launch' in result.stderr.split('its last lines:')[1]
    result = bench('--command', 'no-such-command-here', timeout=60)
    assert result.returncode == 1
    assert 'cannot run no-such-command-here' in result.stderr and 'Traceback' not in result.stderr
