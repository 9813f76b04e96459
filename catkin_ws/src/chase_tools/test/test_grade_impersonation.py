"""The grader judges by its own simulator only: fixture submissions with a node in the simulator's
place. One run of `grade` over them (two at a time, one trial each) is shared by every test here:

  hostile_races_clock             a chaser that works, and a node that publishes its own /clock,
                                  far ahead of the simulator's: not judged, the node named;
  hostile_serves_set_model_state  its robot never moves, and a node serves /gazebo/set_model_state
                                  in the simulator's place, putting the robot beside the ball
                                  whenever the ball is placed: not judged, the node named;
  hostile_serves_as_simulator     the same, its server registered at the master under the
                                  simulator's own name: not judged, the node named;
  hostile_serves_once             the same, under its own name until it has moved the robot,
                                  then under the simulator's with the simulator's own address
                                  again: not judged, the node named.

The grader calls the simulator's services where they were when the world came up, so none
of these nodes moves the robot: had it, the chase would pass.
"""
import pytest

from chase_tools.grading import sandbox
from chase_tools.reach import SURFACE_REACH_M as REACH_GAP_M
from grade_support import failed, grade_variants, items, report_of

GRADED = ('hostile_races_clock', 'hostile_serves_set_model_state', 'hostile_serves_as_simulator',
          'hostile_serves_once')
# A robot that never moved, where the grader placed it, is this far from the ball at least.
PLACED_GAP_M = 0.3
NOT_JUDGED = 'not judged: the simulator was impersonated'

pytestmark = pytest.mark.skipif(sandbox.check() is not None,
                                reason='the grader needs bubblewrap: %s' % sandbox.check())


@pytest.fixture(scope='module')
def graded(tmp_path_factory):
    """(the grade process, {submission: its JSON}, the output folder)."""
    return grade_variants(tmp_path_factory, GRADED, trials=1)


def impersonated_chase(graded, name):
    """The chase item's evidence and the one trial of a submission whose impersonation was seen."""
    _proc, results, _out = graded
    assert 'chase' in failed(results, name), report_of(graded, name)
    chase = items(results, name)['chase']['evidence']
    assert chase.startswith(NOT_JUDGED + ', so no trial counts ('), chase
    (trial,) = results[name]['trials']
    assert not trial['reached'] and trial['error'].startswith(NOT_JUDGED), trial
    return chase, trial


def test_a_clock_from_a_node_of_the_submission_is_refused_and_named(graded):
    _proc, results, _out = graded
    name = 'hostile_races_clock'
    assert {'chase', 'stops_without_ball'} <= set(failed(results, name)), report_of(graded, name)
    chase = items(results, name)['chase']['evidence']
    assert chase.startswith(NOT_JUDGED + ', so no trial counts ('), chase
    assert 'on /clock from /hostile (' in chase and 'which is not the simulator' in chase
    # One line for the node, however often it was started afresh (from a new address each time).
    assert chase.splitlines()[0].count('on /clock from /hostile (') == 1, chase
    assert '/hostile publishes on /clock, which only the simulator may' in chase
    (trial,) = results[name]['trials']
    assert not trial['reached'] and trial['error'].startswith(NOT_JUDGED), trial
    # The trial ran on the simulator's time: the chaser had the time to reach the ball.
    assert trial['closest'] <= REACH_GAP_M, trial
    stop = items(results, name)['stops_without_ball']['evidence']
    assert stop.startswith(NOT_JUDGED) and '/hostile publishes on /clock' in stop, stop
    assert NOT_JUDGED in report_of(graded, name)


def test_a_simulator_service_taken_over_by_a_node_of_the_submission_is_named(graded):
    name = 'hostile_serves_set_model_state'
    chase, trial = impersonated_chase(graded, name)
    assert "/hostile serves /gazebo/set_model_state, the simulator's service" in chase, chase
    # The placements went to the simulator: the robot stood where the grader put it.
    assert trial['closest'] > PLACED_GAP_M, trial
    assert NOT_JUDGED in report_of(graded, name)


def test_a_simulator_service_taken_over_under_the_simulator_s_name_is_named(graded):
    chase, trial = impersonated_chase(graded, 'hostile_serves_as_simulator')
    assert ("/gazebo/set_model_state is served by /hostile (rosrpc://" in chase
            and "registered under the simulator's name" in chase), chase
    assert trial['closest'] > PLACED_GAP_M, trial


def test_a_simulator_service_taken_over_only_while_the_grader_calls_is_named(graded):
    chase, trial = impersonated_chase(graded, 'hostile_serves_once')
    assert ("at a call of /gazebo/set_model_state the master gave the address of /hostile (rosrpc://"
            in chase and "not the simulator's" in chase), chase
    assert trial['closest'] > PLACED_GAP_M, trial
