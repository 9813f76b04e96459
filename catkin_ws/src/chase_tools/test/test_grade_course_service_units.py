"""drive_bot judged against the course's DriveToTarget, or against the submission's own type
when its response differs, whatever ball_chaser the shell sourced. No master."""
import os
import subprocess
import sys

import pytest

from session_fakes import FixedClock, a_session


def test_the_course_service_is_ours_whatever_ball_chaser_the_shell_sourced(tmp_path):
    from ball_chaser.srv import DriveToTarget
    from chase_tools.grading import course_service
    assert DriveToTarget._md5sum == course_service.COURSE_MD5
    # A student's own ball_chaser, first on the path, with another DriveToTarget.
    student_srv = tmp_path / 'ball_chaser' / 'srv'
    student_srv.mkdir(parents=True)
    (tmp_path / 'ball_chaser' / '__init__.py').write_text('')
    (student_srv / '__init__.py').write_text("class DriveToTarget:\n    _md5sum = 'theirs'\n")
    probe = ('from ball_chaser.srv import DriveToTarget as Theirs\n'
             'from chase_tools.grading.course_service import course_drive_to_target\n'
             'print(Theirs._md5sum, course_drive_to_target()._md5sum)\n')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ['PYTHONPATH']]))
    result = subprocess.run([sys.executable, '-c', probe], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ['theirs', course_service.COURSE_MD5]


def a_student_drive_to_target_sourced(monkeypatch):
    """The shell that runs grade has sourced a student's ball_chaser, with another DriveToTarget."""
    import types
    module = types.ModuleType('ball_chaser.srv')
    module.DriveToTarget = type('DriveToTarget', (), {'_md5sum': 'theirs'})
    monkeypatch.setitem(sys.modules, 'ball_chaser.srv', module)


def test_drive_bot_is_judged_against_the_course_service_whatever_the_shell_sourced(tmp_path, monkeypatch):
    from chase_tools.grading import course_service, probe
    session = a_session(tmp_path, monkeypatch)
    a_student_drive_to_target_sourced(monkeypatch)
    session.service_uri = lambda name: 'rosrpc://localhost:1'
    monkeypatch.setattr(probe, 'service_headers', lambda uri, name: {
        'type': 'ball_chaser/DriveToTarget', 'md5sum': course_service.COURSE_MD5})
    session.wait_for_cmd_publishers = lambda: None
    probed = []
    session.probe_drive_bot = lambda srv_type, own=None: probed.append(srv_type)
    session.check_drive_bot()
    assert session.grade.item('drive_bot_service') is None       # not failed on its md5
    assert [srv_type._md5sum for srv_type in probed] == [course_service.COURSE_MD5]


def a_served_srv(tmp_path, monkeypatch, text):
    """A session whose drive_bot serves the type of ball_chaser/srv/DriveToTarget.srv (text)."""
    from chase_tools.grading import probe, service_type
    session = a_session(tmp_path, monkeypatch)
    (tmp_path / 'src' / 'ball_chaser' / 'srv').mkdir(parents=True)
    (tmp_path / 'src' / 'ball_chaser' / 'srv' / 'DriveToTarget.srv').write_text(text)
    md5 = service_type.parse_srv(text, 'ball_chaser/DriveToTarget').md5
    session.service_uri = lambda name: 'rosrpc://localhost:1'
    monkeypatch.setattr(probe, 'service_headers', lambda uri, name: {
        'type': 'ball_chaser/DriveToTarget', 'md5sum': md5})
    session.wait_for_cmd_publishers = lambda: None
    session.counter = None
    return session


def test_a_simulator_taken_over_during_the_service_probe_leaves_it_not_judged(tmp_path, monkeypatch):
    """A node of the submission that takes the simulator's name answers nothing: the probe is not
    judged, and the run goes on to the steps that say who took the name."""
    import rospy
    from chase_tools.grading import checks
    session = a_served_srv(tmp_path, monkeypatch, 'float64 linear_x\nfloat64 angular_z\n---\n'
                                                  'string msg_feedback\n')

    class Refused:
        def unpause(self):
            raise rospy.ServiceException('unable to connect to service: [Errno 111] Connection refused')
    monkeypatch.setattr(checks.chase_graph, 'SimControl', Refused)
    session.models = object()
    session.alive = lambda: True
    session.probe_drive_bot = lambda srv_type, own=None: pytest.fail('probed without sim time')
    session.check_drive_bot()
    item = session.grade.item('drive_bot_service')
    assert item.verdict == 'not judged'
    assert item.evidence.startswith('not judged: the simulator did not answer, so sim time could not run')


def test_drive_bot_of_another_response_is_probed_with_the_submission_s_own_type(tmp_path, monkeypatch):
    session = a_served_srv(tmp_path, monkeypatch, 'float64 linear_x\nfloat64 angular_z\n---\n'
                                                  'float64 linear_x_out\nfloat64 angular_z_out\n')
    probed = []
    session.probe_drive_bot = lambda srv_type, own=None: probed.append((srv_type, own))
    session.check_drive_bot()
    assert session.grade.item('drive_bot_service') is None       # judged by the probe, not the md5
    (srv_type, own), = probed
    assert srv_type._md5sum == own.md5 and srv_type._type == 'ball_chaser/DriveToTarget'
    assert srv_type._response_class.__slots__ == ['linear_x_out', 'angular_z_out']
    assert srv_type._request_class(0.25, -0.35).linear_x == 0.25
    assert any('its response is float64 linear_x_out, float64 angular_z_out where the course\'s is '
               'string msg_feedback (ball_chaser/srv/DriveToTarget.srv)' in note
               for note in session.grade.notes), session.grade.notes


def test_drive_bot_of_another_request_fails_naming_its_fields(tmp_path, monkeypatch):
    session = a_served_srv(tmp_path, monkeypatch,
                           'float64 speed\nfloat64 turn\n---\nstring msg_feedback\n')
    session.probe_drive_bot = lambda srv_type, own=None: pytest.fail('a request of other fields was probed')
    session.check_drive_bot()
    item = session.grade.item('drive_bot_service')
    assert not item.passed
    assert item.evidence.endswith('; its request (ball_chaser/srv/DriveToTarget.srv) has float64 speed, '
                                  'float64 turn, not the course\'s float64 linear_x, float64 angular_z')


class StillSim:
    """What an extra world's warm-up asks of the simulator, doing nothing."""

    def pause(self):
        pass

    def unpause(self):
        pass


def an_extra_world(tmp_path, out):
    """TrialWorld number 2 of a session, its calls to drive_bot recorded in .called."""
    import io
    from chase_tools.grading.session import SessionSpec
    from chase_tools.grading.trial_world import TrialWorld
    spec = SessionSpec(overlay_env={}, overlay_root=str(tmp_path), run_scratch=str(tmp_path / 'run'),
                       out_dir=str(tmp_path / out), robot_package='my_robot',
                       chaser_package='ball_chaser', isolate=False,
                       extra_world={'number': 2, 'robot': 'robot', 'ball': 'ball', 'overlays': {}})
    world = TrialWorld(spec, io.StringIO(), io.StringIO())
    world.called = []
    world.call_drive_bot = lambda srv_type, request, within: world.called.append((srv_type._md5sum, request))
    return world


def test_an_extra_world_warms_its_chaser_up_with_the_course_service(tmp_path, monkeypatch):
    from chase_tools.grading import course_service
    monkeypatch.setattr(os, 'environ', dict(os.environ))
    a_student_drive_to_target_sourced(monkeypatch)
    world = an_extra_world(tmp_path, 'out')
    world.counter = None
    world.warm_up(StillSim(), wall_timeout=0.1)
    assert world.called == [(course_service.COURSE_MD5, (0.0, 0.0))]


def test_an_extra_world_counts_and_warms_up_with_the_submission_s_own_type_as_the_session_does(
        tmp_path, monkeypatch):
    from chase_tools.grading import course_service, service_type
    text = ('float64 linear_x\nfloat64 angular_z\n---\n'
            'float64 linear_x_out\nfloat64 angular_z_out\n')
    own = service_type.parse_srv(text, 'ball_chaser/DriveToTarget', 'ball_chaser/srv/DriveToTarget.srv')

    class Counter:
        def __init__(self, srv_type):
            self.srv_type = srv_type

        def serve_as(self, srv_type):
            self.srv_type = srv_type
    # What the session's own world hands its extra worlds, its stand-in serving its own type.
    session = a_session(tmp_path, monkeypatch)
    session.found.own_service = (own.md5, own)
    session.counter = Counter(service_type.service_class(own))
    share = session.own_service_share()
    assert share == {'type': 'ball_chaser/DriveToTarget', 'text': text}
    session.counter = Counter(course_service.course_drive_to_target())
    assert session.own_service_share() is None         # its stand-in serves the course's
    monkeypatch.setattr(os, 'environ', dict(os.environ))
    world = an_extra_world(tmp_path, 'extra_out')
    world.counter = Counter(course_service.course_drive_to_target())
    world.count_as_the_session({'count_calls': True, 'own_service': share})
    assert world.counter.srv_type._md5sum == own.md5
    assert world.counter.srv_type._response_class.__slots__ == ['linear_x_out', 'angular_z_out']
    world.counter.calls = [(0.0, 0.0, 0.0)]
    world.warm_up(StillSim(), wall_timeout=0.1)
    assert world.called == [(own.md5, (0.0, 0.0))]


def test_the_stand_in_holds_a_call_back_with_an_answer_of_the_type_it_serves():
    """While drive_bot itself is tested, process_image's calls are counted and answered, not
    forwarded: with the course's text, or a response of other fields left at its defaults."""
    from chase_tools.grading import course_service, service_type, trials
    from chase_tools.grading.listeners import CallCounter
    counter = CallCounter.__new__(CallCounter)
    counter.clock, counter.calls, counter.forwarding = FixedClock(), trials.RollingLog(10), False
    counter.srv_type = course_service.course_drive_to_target()
    request = counter.srv_type._request_class(0.4, 0.1)
    assert counter.handle(request).msg_feedback == 'held while drive_bot is tested'
    counter.srv_type = service_type.service_class(service_type.parse_srv(
        'float64 linear_x\nfloat64 angular_z\n---\nfloat64 linear_x_out\nfloat64 angular_z_out\n',
        'ball_chaser/DriveToTarget'))
    answer = counter.handle(counter.srv_type._request_class(0.3, -0.2))
    assert (answer.linear_x_out, answer.angular_z_out) == (0.0, 0.0)
    assert [call[1:] for call in counter.calls.since(0)] == [(0.4, 0.1), (0.3, -0.2)]
