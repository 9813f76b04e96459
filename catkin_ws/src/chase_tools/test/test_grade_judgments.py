"""The grader judges what it claims to: fixture submissions that an earlier grader misjudged.

One run of `grade` over a folder of them (two at a time, one trial each) is
shared by every test here:

  hostile_spoofs_model_states  its robot never moves, and a node of it publishes model states
                               with the robot on the ball: the chase must not pass;
  py_ramping_drive_bot         drive_bot steps /cmd_vel toward what was asked after it answers:
                               the asked command comes out, after others;
  py_rocks_when_ball_gone      once the ball is gone it stops, then drives forward and back to
                               where it stopped and sends a stop again: it did not stop.
"""
import pytest

from chase_tools.grading import sandbox
from grade_support import failed, grade_variants, items, report_of

GRADED = ('hostile_spoofs_model_states', 'py_ramping_drive_bot', 'py_rocks_when_ball_gone')

pytestmark = pytest.mark.skipif(sandbox.check() is not None,
                                reason='the grader needs bubblewrap: %s' % sandbox.check())


@pytest.fixture(scope='module')
def graded(tmp_path_factory):
    """(the grade process, {submission: its JSON}, the output folder)."""
    return grade_variants(tmp_path_factory, GRADED, trials=1)


def test_model_states_from_a_node_of_the_submission_are_refused_and_named(graded):
    _proc, results, _out = graded
    name = 'hostile_spoofs_model_states'
    assert {'chase', 'stops_without_ball'} <= set(failed(results, name)), report_of(graded, name)
    chase = items(results, name)['chase']['evidence']
    assert chase.startswith('not judged: the simulator was impersonated, so no trial counts ('), chase
    assert 'on /gazebo/model_states from /hostile (' in chase and 'which is not the simulator' in chase
    assert '/hostile publishes on /gazebo/model_states, which only the simulator may' in chase
    (trial,) = results[name]['trials']
    assert not trial['reached'] and trial['error'].startswith('not judged: the simulator was impersonated')
    # What the simulator itself said: the robot never moved, so it never came near the ball.
    assert trial['closest'] > 0.3, trial
    assert 'not judged: the simulator was impersonated' in report_of(graded, name)


def test_a_drive_bot_whose_asked_command_comes_after_others_passes(graded):
    _proc, results, _out = graded
    name = 'py_ramping_drive_bot'
    assert failed(results, name) == [], report_of(graded, name)
    evidence = items(results, name)['drive_bot_service']['evidence']
    assert '(0.25, -0.35) -> /cmd_vel (0.25, -0.35)' in evidence, evidence
    assert 'other commands meanwhile' in evidence, evidence


def test_a_robot_that_rocks_once_the_ball_is_gone_and_ends_on_a_stop_fails_to_stop(graded):
    _proc, results, _out = graded
    name = 'py_rocks_when_ball_gone'
    assert failed(results, name) == ['stops_without_ball'], report_of(graded, name)
    evidence = items(results, name)['stops_without_ball']['evidence']
    assert 'motion commands in effect then, the first (0.30, 0.00), the last (0.00, 0.00)' in evidence, evidence
    travelled = float(evidence.split('the robot travelled ')[1].split(' m')[0])
    assert travelled > 0.2, evidence


# A service whose type is not the course's, graded apart (one trial each):
#   py_response_of_velocities   the course's request; the response gives the velocities back
#                               (float64 linear_x_out, float64 angular_z_out);
#   py_other_response           the course's request; the response says whether it published;
#   py_request_of_other_fields  the request is float64 speed, float64 turn.
SERVICES = ('py_response_of_velocities', 'py_other_response', 'py_request_of_other_fields')


@pytest.fixture(scope='module')
def graded_services(tmp_path_factory):
    return grade_variants(tmp_path_factory, SERVICES, trials=1)


def test_a_response_of_other_fields_is_judged_by_what_the_service_does_and_noted(graded_services):
    _proc, results, _out = graded_services
    name = 'py_response_of_velocities'
    result = results[name]
    assert failed(results, name) == [], report_of(graded_services, name)
    evidence = items(results, name)
    drive = evidence['drive_bot_service']['evidence']
    assert drive.startswith('/ball_chaser/command_robot is the submission\'s own ball_chaser/DriveToTarget, '
                            'which takes the course\'s request (float64 linear_x, float64 angular_z) '
                            'and answers with float64 linear_x_out, float64 angular_z_out'), drive
    assert ('(0.25, -0.35) -> /cmd_vel (0.25, -0.35), answer "linear_x_out 0.25, angular_z_out -0.35"'
            in drive), drive
    # process_image's calls went through the grader's stand-in, serving the submission's type.
    calls = evidence['process_image_calls']['evidence']
    assert '/process_image subscribes to /camera/rgb/image_raw and called /ball_chaser/command_robot' in calls
    assert any(note.startswith('calls to /ball_chaser/command_robot counted from') for note in result['notes'])
    # The chase, as for any submission.
    assert result['trials'][0]['reached']
    assert ('/ball_chaser/command_robot takes the course\'s request (float64 linear_x, float64 '
            'angular_z), and its response is float64 linear_x_out, float64 angular_z_out where the '
            'course\'s is string msg_feedback (ball_chaser/srv/DriveToTarget.srv)') in ' '.join(
                result['notes']), result['notes']


def test_a_response_of_one_bool_is_judged_by_what_the_service_does(graded_services):
    _proc, results, _out = graded_services
    name = 'py_other_response'
    assert failed(results, name) == [], report_of(graded_services, name)
    drive = items(results, name)['drive_bot_service']['evidence']
    assert 'answers with bool success' in drive and 'answer "success True"' in drive, drive
    assert any('its response is bool success where the course\'s is string msg_feedback' in note
               for note in results[name]['notes']), results[name]['notes']


def test_a_request_of_other_fields_fails_the_service_naming_them(graded_services):
    _proc, results, _out = graded_services
    name = 'py_request_of_other_fields'
    result = results[name]
    assert failed(results, name) == ['drive_bot_service', 'process_image_calls'], report_of(graded_services, name)
    evidence = items(results, name)
    drive = evidence['drive_bot_service']['evidence']
    assert drive.startswith('the service has type ball_chaser/DriveToTarget (md5 '), drive
    assert drive.endswith('; its request (ball_chaser/srv/DriveToTarget.srv) has float64 speed, '
                          'float64 turn, not the course\'s float64 linear_x, float64 angular_z'), drive
    assert 'its calls could not be counted' in evidence['process_image_calls']['evidence']
    # Its own nodes agree with each other: the chase runs on them, not through the stand-in.
    assert result['trials'][0]['reached']
    assert not any('response' in note for note in result['notes']), result['notes']


# A process_image that calls drive_bot only when the ball's region changes, chased three times.
@pytest.fixture(scope='module')
def graded_on_change(tmp_path_factory):
    return grade_variants(tmp_path_factory, ['py_sends_on_change'], trials=3)


def test_a_node_that_sends_only_on_change_reaches_the_ball_in_every_trial_and_stops(graded_on_change):
    _proc, results, _out = graded_on_change
    name = 'py_sends_on_change'
    trials = results[name]['trials']
    assert len(trials) == 3 and all(trial['reached'] for trial in trials), report_of(graded_on_change, name)
    assert failed(results, name) == [], report_of(graded_on_change, name)
    stop = items(results, name)['stops_without_ball']['evidence']
    assert stop.startswith('the robot was driving toward the ball'), stop
    report = report_of(graded_on_change, name)
    assert 'Each trial starts ball_chaser.launch afresh after the placement' in report, report
