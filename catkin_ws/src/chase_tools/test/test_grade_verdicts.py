"""The grader's verdicts end to end: robots and nodes a teacher would pass, and failing chases
that say why.

One run of `grade` over a folder of fixture submissions (two at a time, two trials each) is
shared by every test here; each test reads what the grader wrote for one submission. The
rules themselves are unit-tested in test_placement.py and test_verdicts.py.
"""
import math
import re

import cv2
import pytest

from chase_tools import drawing
from chase_tools.grading import sandbox
from grade_support import failed, grade_variants, items, report_of

GRADED = ('py_camera_ahead', 'py_stops_short', 'py_sleeps_in_loose_building', 'py_never_calls',
          'py_turns_away', 'py_stops_far', 'py_no_room', 'py_moves_then_stops')

pytestmark = pytest.mark.skipif(sandbox.check() is not None,
                                reason='the grader needs bubblewrap: %s' % sandbox.check())


@pytest.fixture(scope='module')
def graded(tmp_path_factory):
    """(the grade process, {submission: its JSON}, the output folder)."""
    return grade_variants(tmp_path_factory, GRADED, trials=2)


def test_a_camera_1_m_ahead_of_the_base_chases_and_passes(graded):
    _proc, results, _out = graded
    assert failed(results, 'py_camera_ahead') == [], report_of(graded, 'py_camera_ahead')
    assert all(trial['reached'] for trial in results['py_camera_ahead']['trials'])


@pytest.fixture(scope='module')
def graded_close(tmp_path_factory):
    """The creeper once more, with a reach of 5 cm: where does it stop?"""
    return grade_variants(tmp_path_factory, ['py_stops_short'], options=['--reach', '0.05'])


def test_a_robot_that_creeps_up_and_stops_11_cm_short_passes_the_chase(graded, graded_close):
    _proc, results, _out = graded
    result = results['py_stops_short']
    assert 'chase' not in failed(results, 'py_stops_short'), report_of(graded, 'py_stops_short')
    for trial in result['trials']:
        assert trial['reached'] and trial['reason'] == 'came within 15 cm of the ball\'s surface'
    assert result['reach'] == 0.15
    assert 'the robot\'s outline within 0.15 m of the ball\'s surface' in items(results, 'py_stops_short')[
        'chase']['evidence']
    # Where it stops: more than 10 cm from the ball's surface. Straight ahead, the old
    # centre-to-centre reach for this robot (its front 0.345 m + 0.2 m = 0.545 m) needed 10 cm.
    (trial,) = graded_close[1]['py_stops_short']['trials']
    assert not trial['reached'] and trial['reason'].startswith('stopped short at 1'), trial
    assert 0.10 < trial['record']['gap_at_end'] <= 0.13


def test_a_drive_bot_that_sleeps_in_sim_time_passes_in_a_building_saved_as_a_loose_model(graded):
    _proc, results, _out = graded
    name = 'py_sleeps_in_loose_building'
    assert failed(results, name) == [], report_of(graded, name)
    evidence = items(results, name)['drive_bot_service']['evidence']
    assert 'with sim time running: (0.25, -0.35) -> /cmd_vel (0.25, -0.35)' in evidence
    # Each answer waited its 0.1 s of sim time, and the round trip adds what sim time ran meanwhile.
    waits = [float(value) for value in re.findall(r'after ([\d.]+) s of sim time', evidence)]
    assert len(waits) == 2 and all(0.1 <= wait < 1.0 for wait in waits), evidence
    assert not any('no colliders' in note for note in results[name]['notes'])
    assert all(trial['reached'] for trial in results[name]['trials'])


def test_a_process_image_that_never_calls_fails_with_seen_but_no_command(graded):
    _proc, results, _out = graded
    name = 'py_never_calls'
    assert {'chase', 'process_image_calls'} <= set(failed(results, name))
    for trial in results[name]['trials']:
        assert not trial['reached']
        assert trial['reason'] == ('saw the ball but sent no command: no call to /ball_chaser/command_robot '
                                   'and no motion command on /cmd_vel')
        assert trial['record']['white_frames'] > 0 and trial['record']['ball_in_view_at_start']
    report = report_of(graded, name)
    assert 'not reached: saw the ball but sent no command' in report
    assert '  trial 0: saw the ball but sent no command' in items(results, name)['chase']['evidence']


def test_a_robot_that_turns_away_fails_with_turned_away(graded):
    _proc, results, _out = graded
    name = 'py_turns_away'
    assert 'chase' in failed(results, name)
    for trial in results[name]['trials']:
        assert trial['reason'].startswith('turned away: the ball left the camera\'s view at '), trial
        assert trial['record']['ball_in_view_at_start'] and not trial['record']['ball_in_view_at_end']


def test_a_robot_that_stops_far_from_the_ball_fails_with_where_it_stopped(graded):
    _proc, results, _out = graded
    name = 'py_stops_far'
    assert failed(results, name) == ['chase'], report_of(graded, name)
    for trial in results[name]['trials']:
        gap = trial['record']['gap_at_end']
        assert 0.35 < gap < 0.6, trial
        assert trial['reason'] == ('stopped short at %.0f cm of the ball\'s surface (from %.1f s on), with '
                                   'the ball in view' % (100 * gap, trial['record']['stopped_at']))
    assert 'not reached: stopped short at ' in report_of(graded, name)


def test_every_placement_starts_with_the_ball_in_the_robots_view(graded):
    _proc, results, _out = graded
    for name in GRADED:
        for trial in results[name]['trials']:
            if not trial['reached']:
                assert trial['record']['ball_in_view_at_start'], (name, trial)
            assert math.isfinite(trial['closest'])


@pytest.fixture(scope='module')
def graded_incomplete(tmp_path_factory):
    """A class of two submissions the grader cannot build: ROS 2 packages, and ball_chaser alone."""
    return grade_variants(tmp_path_factory, ['ros2_packages', 'py_chaser_only'], options=['--class'])


def test_a_ros2_submission_is_named_so_and_not_judged(graded_incomplete):
    proc, results, out = graded_incomplete
    assert proc.returncode == 1, proc.stdout
    builds = items(results, 'ros2_packages')['builds']
    assert builds['evidence'] == ('not judged: ROS 2 packages (ament): this grader runs ROS 1 '
                                  '(catkin) submissions (ball_chaser, my_robot)')
    assert not builds['passed'] and not builds['judged']
    report = report_of(graded_incomplete, 'ros2_packages')
    assert 'Rubric items (7): 0 passed, 0 failed, 7 not judged.' in report
    assert ('| *NOT JUDGED* | not judged: ROS 2 packages (ament): this grader runs ROS 1 (catkin) '
            'submissions (ball_chaser, my_robot) |') in report
    assert 'no package with' not in report
    summary = (out / 'summary.md').read_text()
    assert '| [ros2_packages](ros2_packages/report.md) | 0 passed, 0 failed, 7 not judged |' in summary


def test_ball_chaser_alone_fails_the_build_and_says_what_is_missing(graded_incomplete):
    _proc, results, out = graded_incomplete
    builds = items(results, 'py_chaser_only')['builds']
    assert builds['evidence'] == ('not built: ball_chaser but no robot package (no package with '
                                  'launch/world.launch)')
    assert not builds['passed'] and builds['judged']
    report = report_of(graded_incomplete, 'py_chaser_only')
    assert 'Rubric items (7): 0 passed, 1 failed, 6 not judged.' in report
    assert ('| **FAIL** | not built: ball_chaser but no robot package (no package with '
            'launch/world.launch) |') in report
    assert '| *NOT JUDGED* | not run: the submission is incomplete |' in report
    summary = (out / 'summary.md').read_text()
    assert '| [py_chaser_only](py_chaser_only/report.md) | 0 passed, 1 failed, 6 not judged |' in summary


def test_a_world_with_no_room_for_a_trial_is_not_judged_and_pictured(graded):
    _proc, results, out = graded
    chase = {item['name']: item for item in results['py_no_room']['items']}['chase']
    assert chase['judged'] is False and chase['passed'] is False
    assert chase['evidence'].startswith('not judged: no placement could be drawn in this world')
    # It says why the draws were refused, not a question.
    assert 'refused for: ' in chase['evidence'] and 'is there a room' not in chase['evidence']
    assert results['py_no_room']['world_png'] == 'world.png'
    report = (out / 'py_no_room' / 'report.md').read_text()
    assert '![the world](world.png)' in report
    picture = cv2.imread(str(out / 'py_no_room' / 'world.png'))
    # The closet's walls, drawn in the obstacle colour, around the robot.
    assert (picture == drawing.OBSTACLE_COLOR[::-1]).all(axis=2).sum() > 500


def test_a_move_then_a_stop_from_one_callback_never_sets_the_robot_off(graded):
    """As in Gazebo: the stop that follows each move at once is the command in effect, so the
    robot stays put. The chase fails, and stopping without the ball cannot be shown."""
    _proc, results, _out = graded
    found = items(results, 'py_moves_then_stops')
    assert not found['chase']['passed']
    assert all(trial['record']['moved_m'] < 0.05 for trial in results['py_moves_then_stops']['trials'])
    stop = found['stops_without_ball']
    assert stop['judged'] is False, stop
    assert 'the robot did not set off toward it' in stop['evidence'] and 'though it was sent' in stop['evidence']
