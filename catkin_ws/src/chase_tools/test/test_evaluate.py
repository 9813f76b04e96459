"""evaluate: seeded placements for the project's robot, the summary table, and a short batch end to end.

The placement rule itself is tested in test_placement.py."""
import math
import os
import pathlib
import random
import shutil
import socket

import pytest

from chase_tools import evaluate, placement
from chase_tools.evaluate import TrialResult, format_table, summarize
from chase_tools.placement import FreeSpace, Placement
from flatsim.loading.sdf_world import load_world

SRC = pathlib.Path(__file__).resolve().parents[2]
CHASE_HOUSE = SRC / 'my_robot' / 'worlds' / 'chase_house.world'

@pytest.fixture(scope='module')
def house():
    return load_world(str(CHASE_HOUSE))


@pytest.fixture(scope='module')
def course_robot():
    """The robot world.launch spawns, from the robot_description it sets."""
    return evaluate.launched_robot(str(CHASE_HOUSE))


def test_the_same_seed_gives_the_same_placements(house, course_robot):
    def plan(count, seed):
        return placement.plan_placements(house, course_robot, count, seed, 'white_ball', keep_out=['my_robot'])
    first, _notes = plan(5, 7)
    assert first == plan(5, 7)[0]
    assert first != plan(5, 8)[0]
    # Trial i's placement does not depend on how many trials there are.
    assert plan(2, 7)[0] == first[:2]
    assert evaluate.placements_for(str(CHASE_HOUSE), 5, 7) == (first, [])


def test_the_project_robots_placements_have_the_whole_ball_in_its_camera_view(house, course_robot):
    """The robot that world.launch spawns: camera 0.255 m ahead of its base, 1.396 rad wide."""
    assert (course_robot.camera.x, course_robot.camera.hfov) == (pytest.approx(0.255), pytest.approx(1.3962634))
    space = FreeSpace(house, keep_out={'white_ball', 'my_robot'})
    radius, ball_z = placement.ball_of(house, 'white_ball')
    places, _notes = evaluate.placements_for(str(CHASE_HOUSE), 30, 3)
    for place in places:
        robot, ball = (place.robot_x, place.robot_y), (place.ball_x, place.ball_y)
        camera = course_robot.camera.world(*robot, place.robot_yaw)
        assert space.clearance(*ball) >= 0.5 and space.enclosed(*robot) and space.enclosed(*ball)
        assert space.outline_clear(course_robot.outline(*robot, place.robot_yaw), 0.25 - 1e-9)
        assert 1.0 <= math.hypot(ball[0] - camera[0], ball[1] - camera[1]) <= 4.0
        assert placement.whole_ball_in_view(course_robot.camera, camera, ball, ball_z, radius)
        assert space.ball_edges_visible(camera[:2], ball, radius)
        assert space.in_sight(robot, ball, course_robot.half_width)
        # Inside the house's outer walls (x -3..7, y -4..4).
        assert -3 < place.robot_x < 7 and -4 < place.robot_y < 4


def test_summary_counts_reached_trials_and_takes_percentiles_of_their_times():
    results = [TrialResult(i, 'course', True, float(t), 0.3) for i, t in enumerate(range(1, 11))]
    results.append(TrialResult(10, 'course', False, None, 0.9))
    results.append(TrialResult(0, 'proportional', False, None, 1.5, error='boom'))
    assert summarize(results, 'course') == (10, 11, 5.5, pytest.approx(9.1), 10.0)
    assert summarize(results, 'proportional') == (0, 1, None, None, None)
    table = format_table(results, ('proportional', 'course')).splitlines()
    assert table[0].split() == ['proportional', 'course']
    assert table[1].split() == ['success', 'rate', '0/1', '(0%)', '10/11', '(91%)']
    assert table[2].split() == ['time', 'to', 'ball', 'p50', '-', '5.5', 's']
    assert table[-1].split() == ['could', 'not', 'run', '1', '0']


def test_bad_arguments_are_refused():
    with pytest.raises(SystemExit):
        evaluate.parse_args(['--trials', '0'])
    with pytest.raises(SystemExit):
        evaluate.parse_args(['--timeout', '-1'])
    assert evaluate.parse_args(['--trials', '3', '--seed', '2']).modes == list(evaluate.MODES)


def test_placement_distance():
    assert Placement(0.0, 0.0, 0.0, 3.0, 4.0).ball_distance == 5.0


# -- end to end: needs the built workspace (roslaunch, my_robot, ball_chaser) --

needs_ros = pytest.mark.skipif(
    shutil.which('roslaunch') is None or 'catkin_ws' not in os.environ.get('ROS_PACKAGE_PATH', ''),
    reason='needs the built workspace: source env.sh first')


def free_ports(count):
    """The first of count consecutive ports that nothing listens on, below the ephemeral range
    (where any outgoing connection may take one of them while the batch starts)."""
    rng = random.Random()
    while True:
        base = rng.randrange(13000, 30000 - count)
        try:
            for port in range(base, base + count):
                with socket.socket() as sock:
                    sock.bind(('127.0.0.1', port))
        except OSError:
            continue
        return base


@pytest.fixture(scope='module')
def two_batches(tmp_path_factory):
    """The same 2-trial batch (both modes) run twice, with its printed output: once with a world per
    mode, once with a world per mode and placement."""
    runs = []
    for repeat, jobs in enumerate((2, 4)):
        base_port = free_ports(jobs)
        out_path = tmp_path_factory.mktemp('evaluate%d' % repeat) / 'out.txt'
        args = evaluate.parse_args(['--trials', '2', '--seed', '5', '--jobs', str(jobs), '--timeout', '40',
                                    '--base-port', str(base_port), '--log-dir', str(out_path.parent)])
        with open(out_path, 'w') as out:
            results = evaluate.evaluate(args, out=out)
        runs.append((results, out_path.read_text()))
    return runs


@needs_ros
def test_a_short_batch_prints_the_table_and_every_trial_reaches_the_ball(two_batches):
    results, text = two_batches[0]
    assert [(r.index, r.mode) for r in results] == [(0, 'proportional'), (0, 'course'),
                                                    (1, 'proportional'), (1, 'course')]
    assert all(r.reached and not r.error for r in results), text
    assert 'success rate      2/2 (100%)      2/2 (100%)' in text
    assert 'time to ball p90' in text


@needs_ros
def test_the_same_seed_gives_the_same_table(two_batches):
    """Lockstep: the same trials give the same times to the ball, bit for bit, whichever worker
    ran them and in whatever order (the second batch splits the work differently)."""
    (first, first_text), (second, second_text) = two_batches
    assert [(r.index, r.mode, r.reached, r.time_to_ball) for r in first] == \
        [(r.index, r.mode, r.reached, r.time_to_ball) for r in second]
    table = first_text[first_text.index('reach '):]
    assert table == second_text[second_text.index('reach '):]


def test_each_mode_is_split_among_the_workers_and_every_trial_runs_once():
    placements = [Placement(0.0, 0.0, 0.0, float(i), 1.0) for i in range(5)]
    specs = evaluate.worker_specs(placements, ['proportional', 'course'], 4, 100, 1, 60.0, 0.4, True,
                                  0.0, 'w.world', '/tmp')
    assert [(s.mode, [i for i, _ in s.trials]) for s in specs] == [
        ('proportional', [0, 2, 4]), ('proportional', [1, 3]), ('course', [0, 2, 4]), ('course', [1, 3])]
    assert [s.port for s in specs] == [100, 101, 102, 103]
    assert len({s.log_path for s in specs}) == 4
    one = evaluate.worker_specs(placements, ['course'], 1, 100, 1, 60.0, 0.4, True, 0.0, 'w.world', '/tmp')
    assert [[i for i, _ in s.trials] for s in one] == [[0, 1, 2, 3, 4]]


@pytest.mark.parametrize('argv, message', [
    (['--base-port', '70000'], 'argument --base-port: 70000 must be at most 65535'),
    (['--base-port', '65535', '--jobs', '2'], 'argument --base-port: 2 workers need ports 65535 to 65536'),
    (['--seed', '-1'], 'argument --seed: -1 must be at least 0'),
    (['--seed', '4294967296'], 'argument --seed: 4294967296 must be at most 2147483647'),
    (['--jobs', '0'], 'argument --jobs: 0 must be at least 1'),
    (['--reach', 'nan'], "argument --reach: 'nan' is not a finite number"),
    (['--log-dir', '/proc/nope'], 'argument --log-dir: cannot make the folder /proc/nope'),
])
def test_arguments_that_cannot_work_are_argument_errors(argv, message, capsys):
    with pytest.raises(SystemExit) as stopped:
        evaluate.parse_args(argv)
    assert stopped.value.code == 2
    assert 'evaluate: error: %s' % message in capsys.readouterr().err


def test_the_last_port_serves_one_worker():
    args = evaluate.parse_args(['--base-port', '65535', '--jobs', '1', '--modes', 'course'])
    assert evaluate.worker_count(args.trials, args.modes, args.jobs) == 1


def test_a_worker_whose_port_is_taken_says_so_and_joins_nothing(tmp_path, monkeypatch):
    # run_worker points this process's ROS variables at its port; a copy keeps the test's own.
    monkeypatch.setattr(os, 'environ', dict(os.environ))
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as held:
        held.bind(('', 0))
        held.listen()
        port = held.getsockname()[1]
        spec = evaluate.WorkerSpec('course', ((0, Placement(0.0, 0.0, 0.0, 2.0, 0.0)),), port, 0, 10.0, 0.4,
                                   True, 0.0, str(CHASE_HOUSE), str(tmp_path / 'worker.log'))
        results = []
        evaluate.run_worker(spec, results.append)
    assert [(r.index, r.reached, r.error) for r in results] == [
        (0, False, 'PortTaken: port %d is taken, most likely by another ROS master' % port)]


def test_lockstep_as_fast_as_it_goes_is_the_default_and_real_time_is_asked_for():
    args = evaluate.parse_args([])
    assert (args.real_time, args.real_time_factor) == (False, 0.0)
    args = evaluate.parse_args(['--real-time'])
    assert (args.real_time, args.real_time_factor) == (True, 1.0)
    with pytest.raises(SystemExit):
        evaluate.parse_args(['--real-time-factor', 'nan'])
