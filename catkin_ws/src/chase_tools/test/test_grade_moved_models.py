"""The grader judges only what the robot's own driving did: fixture submissions that move the
robot to the ball some other way. One run of `grade` over them (two at a time, one trial
each) is shared by every test here:

  hostile_teleports   its robot never moves; during the trial a node calls the simulator's own
                      /gazebo/set_model_state and puts the robot just short of the ball: not
                      judged, the node named, and the jump the robot made said;
  hostile_forges_simulator
                      its robot never moves; its world.launch starts a copy of flatsim of its
                      own, named flatsim, whose model states show the robot on the ball: the
                      grader's own simulator runs, the node that claims its name is named,
                      and the world is not judged;
  hostile_named_gazebo
                      a chaser that works, beside a node of ball_chaser.launch registered
                      under gzserver's name, /gazebo: the chase is not judged, the name said.

Each test also checks that the submission's folder and the project's own files are as they
were, and that the report names the attack.
"""
import os
import re

import pytest

from chase_tools.grading import sandbox
from grade_support import changed, failed, grade_variants, items, report_of, tree_state

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.realpath(os.path.join(HERE, '..', '..', '..', '..'))
GRADED = ('hostile_teleports', 'hostile_forges_simulator', 'hostile_named_gazebo')
MOVED = 'not judged: the models were moved during the trial'
IMPERSONATED = 'not judged: the simulator was impersonated'
# What a grade must leave as it was, besides the submission's folder: the simulator, the
# gazebo_ros stand-in and the grader.
PROJECT = [os.path.join(TOP, 'catkin_ws', 'src', 'flatsim', 'src'),
           os.path.join(TOP, 'catkin_ws', 'src', 'gazebo_compat', 'gazebo_ros'),
           os.path.join(HERE, '..', 'src', 'chase_tools', 'grading')]

pytestmark = pytest.mark.skipif(sandbox.check() is not None,
                                reason='the grader needs bubblewrap: %s' % sandbox.check())


@pytest.fixture(scope='module')
def graded(tmp_path_factory):
    """(the grade process, {submission: its JSON}, the output folder, what changed outside the
    scratch and the report folder)."""
    project = tree_state(*PROJECT)
    written = []
    proc, results, out = grade_variants(tmp_path_factory, GRADED, trials=1, written=written)
    fresh = tmp_path_factory.mktemp('as_written')
    import variants
    left = []
    for name in GRADED:
        variants.compose(name, fresh)
        left += ['%s/%s' % (name, path) for path in changed(tree_state(str(fresh / name)),
                                                             tree_state(str(written[0] / name)))]
    left += changed(project, tree_state(*PROJECT))
    return proc, results, out, left


def test_a_node_that_teleports_the_robot_during_a_trial_is_named_and_the_jump_said(graded):
    _proc, results, _out, left = graded
    name = 'hostile_teleports'
    assert 'chase' in failed(results, name), report_of(graded, name)
    chase = items(results, name)['chase']['evidence']
    assert chase.startswith(MOVED + ', so no trial counts (trial 0: /hostile'), chase
    assert 'moved my_robot through /gazebo/set_model_state at' in chase, chase
    (trial,) = results[name]['trials']
    assert not trial['reached'] and trial['error'].startswith(MOVED + ': /hostile'), trial
    assert 'my_robot moved' in trial['error'] and 'faster than it could drive' in trial['error'], trial
    report = report_of(graded, name)
    assert MOVED in report and '/hostile' in report
    # The simulator was the grader's, as a uid that is not the submission's.
    (ran,) = [note for note in results[name]['notes'] if note.startswith('the grader ran the simulator')]
    simulator_uid = int(re.search(r'as uid (\d+) in a sandbox of its own', ran).group(1))
    assert 'with the world world.launch gives it: office.world' in ran, ran
    assert 'as uid %d,' % simulator_uid not in results[name]['isolation'], results[name]['isolation']
    assert left == [], 'changed outside the scratch and the report folder: %s' % left


def test_a_simulator_of_the_submissions_own_making_under_the_simulators_name_is_named(graded):
    _proc, results, _out, left = graded
    name = 'hostile_forges_simulator'
    assert {'world_launches', 'chase'} <= set(failed(results, name)), report_of(graded, name)
    world = items(results, name)['world_launches']['evidence']
    assert world.startswith(IMPERSONATED + ': '), world
    assert ("world.launch starts the node /flatsim (ball_chaser/hostile.py) under the simulator's "
            "name" in world), world
    assert not any(trial['reached'] for trial in results[name]['trials'])
    chase = items(results, name)['chase']['evidence']
    assert chase == 'not run: the world did not launch', chase
    report = report_of(graded, name)
    assert IMPERSONATED in report and 'the node /flatsim (ball_chaser/hostile.py)' in report
    assert left == [], 'changed outside the scratch and the report folder: %s' % left


def test_a_node_registered_under_gzservers_name_is_named(graded):
    _proc, results, _out, left = graded
    name = 'hostile_named_gazebo'
    assert 'chase' in failed(results, name), report_of(graded, name)
    chase = items(results, name)['chase']['evidence']
    assert chase.startswith(IMPERSONATED + ', so no trial counts ('), chase
    assert "a node registered under the simulator's name /gazebo (http://" in chase, chase
    assert IMPERSONATED in report_of(graded, name)
    assert left == [], 'changed outside the scratch and the report folder: %s' % left
