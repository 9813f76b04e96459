"""The grader end to end, on fixture submissions written for these tests.

One run of `grade` over a folder of them (two at a time) is shared by every
test here; each test reads what the grader wrote for one submission.
"""
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import time

import pytest

from chase_tools.grading import sandbox
from chase_tools.grading.overlay import Overlay
from chase_tools.grading.scratch import Scratch
from grade_support import failed, grade_variants, items, processes_of_uid, report_of, variants
import chase_variants  # on the fixtures' path, which grade_support puts on sys.path

GRADED = ('cpp_correct', 'py_correct', 'py_wrong_service', 'py_wrong_type', 'py_never_stops',
          'cpp_broken', 'py_escape_build', 'py_escape', 'py_chaser_includes_world', 'py_repository',
          'py_stray_link', 'py_world_launch_in_worlds')
COURSE_MD5 = 'c8652349d2a34a90a09475339e2a93d9'  # float64 linear_x, angular_z -> string msg_feedback

pytestmark = pytest.mark.skipif(sandbox.check() is not None,
                                reason='the grader needs bubblewrap: %s' % sandbox.check())


@pytest.fixture(scope='module')
def graded(tmp_path_factory):
    """(the grade process, {submission: its JSON}, the output folder)."""
    def clear_escapes():
        for path in variants.ESCAPE_FILES:
            if os.path.exists(path):
                os.remove(path)
    return grade_variants(tmp_path_factory, GRADED, before=clear_escapes)


def test_a_folder_is_graded_one_submission_each(graded):
    proc, results, out = graded
    assert sorted(results) == sorted(GRADED), proc.stdout
    assert proc.returncode == 1, proc.stdout          # some submissions fail items
    assert '%d submissions' % len(GRADED) in proc.stdout and '2 at a time' in proc.stdout
    with open(os.path.join(out, 'summary.md')) as stream:
        summary = stream.read()
    assert all('[%s](%s/report.md)' % (name, name) in summary for name in GRADED)


@pytest.mark.parametrize('name', ['cpp_correct', 'py_correct'])
def test_a_correct_submission_passes_every_item(graded, name):
    _proc, results, out = graded
    result = results[name]
    assert failed(results, name) == [], report_of(graded, name)
    assert result['success_rate'] == 1.0
    assert 'chases in lockstep, as fast as the nodes answer' in result['notes']
    trial = result['trials'][0]
    assert trial['reached'] and 0 < trial['time_to_ball'] < 30
    assert os.path.getsize(os.path.join(out, name, trial['png'])) > 1000
    evidence = items(results, name)
    assert 'message targets built first: ball_chaser_generate_messages' in evidence['builds']['evidence']
    assert 'left out (no display): rviz' in evidence['world_launches']['evidence']
    assert '(0.25, -0.35) -> /cmd_vel (0.25, -0.35)' in evidence['drive_bot_service']['evidence']
    assert '/process_image subscribes to /camera/rgb/image_raw' in evidence['process_image_calls']['evidence']
    assert 'every command in effect then was a stop, the last (0.00, 0.00)' in \
        evidence['stops_without_ball']['evidence']
    report = report_of(graded, name)
    assert '| `chase` | seeded placements are chased to the ball | PASS |' in report
    assert '![trial 0](trial_00.png)' in report


def test_the_courses_other_rows_are_judged_from_the_files_and_the_run(graded):
    _proc, results, _out = graded
    cpp = {row['name']: row for row in results['cpp_correct']['course_rows']}
    python = {row['name']: row for row in results['py_correct']['course_rows']}
    assert cpp['cpp_nodes']['passed'] and cpp['cpp_nodes']['counted']
    assert not python['cpp_nodes']['passed'] and python['cpp_nodes']['judged']
    assert python['cpp_nodes']['evidence'].startswith('drive_bot and process_image are Python')
    # What the run saw: the robot xacro made, where it was spawned, the world it launched.
    robot = cpp['robot_differs_from_sample']
    assert robot['passed'] and robot['evidence'].startswith('the spawned robot `'), robot
    assert '0.36 x 0.24 x 0.08 m (sample 0.4 x 0.2 x 0.1 m)' in robot['evidence']
    assert cpp['robot_housed_in_world']['judged']
    assert cpp['robot_housed_in_world']['evidence'].startswith('spawned at (0.00, 0.00)')
    assert cpp['building_editor_world']['evidence'].startswith('the world office.world holds `')
    # A submission that never built has no spawned robot to compare.
    broken = {row['name']: row for row in results['cpp_broken']['course_rows']}
    assert not broken['robot_differs_from_sample']['judged']
    assert broken['cpp_nodes']['passed']
    assert "## The course's other rubric rows" in report_of(graded, 'cpp_correct')


def test_a_world_launch_outside_launch_is_run_as_roslaunch_finds_it_and_named_in_a_note(graded):
    _proc, results, _out = graded
    name = 'py_world_launch_in_worlds'
    assert failed(results, name) == [], report_of(graded, name)
    assert ('my_robot/worlds/world.launch lies outside launch/, where the course keeps it; '
            'roslaunch finds it there all the same') in results[name]['notes']


def test_the_wrong_service_name_fails_the_service_and_the_calls(graded):
    _proc, results, _out = graded
    assert failed(results, 'py_wrong_service') == ['drive_bot_service', 'process_image_calls']
    evidence = items(results, 'py_wrong_service')
    assert evidence['drive_bot_service']['evidence'].startswith(
        '/ball_chaser/command_robot is not served; the submission\'s nodes serve '
        '/command_robot (ball_chaser/DriveToTarget)')
    assert 'never called /ball_chaser/command_robot' in evidence['process_image_calls']['evidence']


def test_a_service_of_another_type_fails_with_both_md5s(graded):
    _proc, results, _out = graded
    assert failed(results, 'py_wrong_type') == ['drive_bot_service', 'process_image_calls']
    evidence = items(results, 'py_wrong_type')['drive_bot_service']['evidence']
    assert evidence.startswith('the service has type ball_chaser/DriveToTarget (md5 ')
    assert "not the course's ball_chaser/DriveToTarget" in evidence
    assert 'md5 %s)' % COURSE_MD5 in evidence
    assert any('is not the course\'s (md5 %s)' % COURSE_MD5 in note
               for note in results['py_wrong_type']['notes'])
    # Its own nodes agree with each other: the chase runs on them, not through the stand-in.
    assert results['py_wrong_type']['trials'][0]['reached']


def test_a_ball_chaser_launch_that_includes_world_launch_is_launched_alone(graded):
    _proc, results, out = graded
    name = 'py_chaser_includes_world'
    assert failed(results, name) == [], report_of(graded, name)
    assert items(results, name)['world_launches']['evidence'].endswith(
        'started by ball_chaser.launch, which includes world.launch')
    assert ('ball_chaser/launch/ball_chaser.launch includes my_robot/launch/world.launch, so '
            'ball_chaser.launch was launched alone, as the submission runs it, and world.launch '
            'was not launched before it') in results[name]['notes']
    # One simulator: world.launch was not launched beside it. ball_chaser.launch is started
    # afresh for the trial and for the stop check, each time with the one simulator of its own.
    assert not os.path.exists(os.path.join(out, name, 'logs', 'world_launch.log'))
    with open(os.path.join(out, name, 'logs', 'ball_chaser_launch.log')) as stream:
        log = stream.read()
    starts = log.count('process[process_image-')
    assert starts == 3 and log.count('process[flatsim-') == starts, log
    assert 'another Gazebo process' not in log


def test_a_repository_is_one_submission_graded_in_the_folder_that_holds_it(graded):
    _proc, results, _out = graded
    name = 'py_repository'
    assert failed(results, name) == [], report_of(graded, name)
    assert results[name]['folder'] == 'Project 2'
    assert results[name]['ignored'] == ['Project 1/my_robot', 'backup/ball_chaser']
    assert ('Graded folder: `Project 2`; not graded: `Project 1/my_robot`, `backup/ball_chaser`'
            in report_of(graded, name))


def test_a_link_out_of_the_submission_is_left_out_of_the_copy_and_named(graded):
    _proc, results, _out = graded
    name = 'py_stray_link'
    # Followed, the link would give roslaunch two world.launch files in my_robot.
    assert failed(results, name) == [], report_of(graded, name)
    assert ("links left out of the grader's copy (roslaunch would follow them out of the "
            "submission): my_robot/upstream -> %s (points outside the submission)"
            % chase_variants.OUTSIDE_ROBOT) in results[name]['notes']


def test_a_robot_that_never_stops_fails_that_item_only(graded):
    _proc, results, _out = graded
    assert failed(results, 'py_never_stops') == ['stops_without_ball']
    evidence = items(results, 'py_never_stops')['stops_without_ball']['evidence']
    assert 'every command in effect then was a stop' not in evidence
    assert 'motion command in effect then' in evidence, evidence
    assert 'the ball was taken away' in evidence
    # Its server node is not named like drive_bot; the grader finds out and says so.
    assert any(note.startswith('command_server serves /ball_chaser/command_robot but was taken for '
                               'a client') for note in results['py_never_stops']['notes'])


def test_a_build_error_is_a_failed_item_with_its_log_lines(graded):
    _proc, results, _out = graded
    evidence = items(results, 'cpp_broken')
    assert not evidence['builds']['passed']
    lines = evidence['builds']['evidence'].splitlines()
    assert any('drive_bot.cpp' in line and 'error:' in line for line in lines[1:]), lines
    assert evidence['chase']['evidence'] == 'not run: the build failed'
    assert results['cpp_broken']['success_rate'] == 0.0


def test_writing_outside_the_scratch_during_the_build_fails_the_build(graded):
    _proc, results, _out = graded
    assert not os.path.exists('/tmp/grade_escape_build')
    evidence = items(results, 'py_escape_build')['builds']
    assert not evidence['passed']
    assert 'Read-only file system' in evidence['evidence'] or 'grade_escape_build' in evidence['evidence']


def test_xacro_and_nodes_that_reach_outside_fail_their_items(graded):
    _proc, results, _out = graded
    for path in variants.ESCAPE_FILES:
        assert not os.path.exists(path), path
    evidence = items(results, 'py_escape')
    assert evidence['builds']['passed']
    assert not evidence['world_launches']['passed']
    assert "Read-only file system: '/tmp/grade_escape_xacro'" in evidence['world_launches']['evidence']
    assert not evidence['drive_bot_service']['passed']
    assert 'Network is unreachable' in evidence['drive_bot_service']['evidence']
    assert not evidence['process_image_calls']['passed']
    assert "Read-only file system: '/tmp/grade_escape_node'" in evidence['process_image_calls']['evidence']


def test_code_built_on_ubuntu_20_04_builds_and_the_grader_says_how(tmp_path):
    """No add_dependencies on its generated header, and std::accumulate without <numeric>."""
    path = variants.compose('cpp_ubuntu20', tmp_path / 'submission')
    scratch = Scratch.create(str(tmp_path), 'scratch_')
    confinement = sandbox.Confinement.create(scratch.grader)
    if confinement.switch_user:
        scratch.owner = (confinement.uid, confinement.gid)
    box = sandbox.Sandbox(scratch.build, visible=sandbox.environment_paths(os.environ),
                          own_network=True, confinement=confinement)
    ws = Overlay(scratch.workspace, sandbox=box)
    for package in ('my_robot', 'ball_chaser'):
        ws.add(os.path.join(path, package))
    scratch.hand_over(scratch.build)
    outcome = ws.build_robustly()
    assert outcome.passed, outcome.log[-3000:]
    assert outcome.message_targets == ['ball_chaser_generate_messages']
    assert outcome.forced_headers == ['numeric']
    said = ' '.join(outcome.steps)
    assert 'message targets built first' in said
    assert '<numeric> for accumulate' in said and '-include numeric' in said
    assert os.access(os.path.join(ws.root, 'devel', 'lib', 'ball_chaser', 'process_image'), os.X_OK)


def tree_digest(top):
    """{path: sha256 or link target} of every file under top."""
    found = {}
    for root, dirs, files in os.walk(top):
        for name in dirs + files:
            path = os.path.join(root, name)
            if os.path.islink(path):
                found[path] = os.readlink(path)
            elif os.path.isfile(path):
                with open(path, 'rb') as stream:
                    found[path] = hashlib.sha256(stream.read()).hexdigest()
    return found


PROJECT_LAUNCH_FILES = [os.path.join(chase_variants.OUTSIDE_ROBOT, os.pardir, package, 'launch', name)
                        for package, name in (('my_robot', 'world.launch'),
                                              ('ball_chaser', 'ball_chaser.launch'))]


def test_without_isolation_a_correct_submission_is_graded_and_the_report_says_so(tmp_path):
    """--no-isolation, for a container that isolates the submission itself: no sandbox, so the
    launch files are prepared in the built copy itself, and its master gets a free port."""
    path = variants.compose('py_correct', tmp_path / 'submission')
    watched = dict(tree_digest(path), **{launch: tree_digest(os.path.dirname(launch))
                                        for launch in PROJECT_LAUNCH_FILES})
    scratch = tmp_path / 'scratch'
    scratch.mkdir()
    proc = subprocess.run(['grade', path, '--no-isolation', '--trials', '1', '--timeout', '30',
                           '--scratch', str(scratch), '--output', str(tmp_path / 'report'),
                           '--json', str(tmp_path / 'grade.json')],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=900,
                          check=False)
    assert proc.returncode == 0, proc.stdout
    with open(tmp_path / 'grade.json') as stream:
        result = json.load(stream)
    assert [item['name'] for item in result['items'] if not item['passed']] == [], proc.stdout
    assert result['trials'][0]['reached']
    assert result['isolation'] == ('none (--no-isolation): the container must isolate the '
                                   'submission and bound its disk')
    evidence = {item['name']: item['evidence'] for item in result['items']}
    assert 'left out (no display): rviz' in evidence['world_launches']
    assert 'calls to /ball_chaser/command_robot counted from process_image' in ' '.join(result['notes'])
    assert not any('bubblewrap' in note or 'uid' in note for note in result['notes'])
    # The fixture robot stands: its line is advice, not an item.
    [advice] = result['advisories']
    assert advice.startswith('robot stability: stable: centre of mass (0.016, 0.000) m of 14.10 kg is '
                             '0.034 m inside the support polygon')
    assert 'Advisory, not a rubric item: %s' % advice in (tmp_path / 'report' / 'report.md').read_text()
    # Nothing outside the scratch folder changed, and the scratch folder is gone.
    assert dict(tree_digest(path), **{launch: tree_digest(os.path.dirname(launch))
                                      for launch in PROJECT_LAUNCH_FILES}) == watched
    assert os.listdir(str(scratch)) == []


def test_grade_is_a_command_and_a_rosrun_target():
    assert shutil.which('grade', path=os.environ['PATH']).endswith(os.path.join('devel', 'bin', 'grade'))
    result = subprocess.run(['rosrun', 'chase_tools', 'grade', '--help'], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, timeout=60, check=False)
    assert result.returncode == 0 and 'usage: grade' in result.stdout, result.stdout


def test_run_sh_sets_up_then_grades(tmp_path):
    """docs/teaching.md's `./run.sh grade PATH ...`: setup.sh (its steps done, skipped), then grade
    itself, which here refuses a PATH that is not a folder."""
    top = os.path.abspath(os.path.join(os.path.dirname(__file__), *[os.pardir] * 4))
    result = subprocess.run([os.path.join(top, 'run.sh'), 'grade', str(tmp_path / 'missing')],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300,
                            check=False)
    assert '[setup] done' in result.stdout, result.stdout
    assert result.returncode == 2 and 'missing is not a folder' in result.stdout, result.stdout


def test_run_sh_hands_help_to_grade_not_to_catkins_setup(tmp_path):
    """catkin's setup script, which run.sh sources, reads the arguments it is sourced with."""
    top = os.path.abspath(os.path.join(os.path.dirname(__file__), *[os.pardir] * 4))
    result = subprocess.run([os.path.join(top, 'run.sh'), 'grade', '--help'],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300,
                            check=False)
    assert result.returncode == 0 and 'usage: grade' in result.stdout, result.stdout


def processes_mentioning(text):
    """The pids of the processes whose command line or environment holds text."""
    found = []
    for entry in os.listdir('/proc'):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        for part in ('cmdline', 'environ'):
            try:
                with open('/proc/%s/%s' % (entry, part), 'rb') as stream:
                    if text.encode() in stream.read():
                        found.append(int(entry))
                        break
            except OSError:
                continue
    return found


def test_a_class_grade_stopped_by_sigterm_keeps_what_it_finished_and_leaves_nothing_running(tmp_path):
    """What Slurm's time limit or scancel does: SIGTERM while the second of two submissions is
    graded. The first one's result is on disk, the second's report says it was stopped, the
    class's summary says so, and no process of the grade is left."""
    folder = tmp_path / 'class'
    folder.mkdir()
    variants.compose('py_correct', folder)
    os.rename(folder / 'py_correct', folder / 'alice')
    variants.compose('py_correct', folder)
    os.rename(folder / 'py_correct', folder / 'bob')
    out = tmp_path / 'report'
    proc = subprocess.Popen(['grade', str(folder), '--class', '--jobs', '1', '--trials', '1',
                             '--timeout', '20', '--output', str(out), '--json', str(tmp_path / 'all.json')],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    bobs_session = out / 'bob' / 'logs' / 'session.log'
    try:
        deadline = time.monotonic() + 600
        # Stopped once bob's world is up: his master, simulator and nodes run.
        while time.monotonic() < deadline and proc.poll() is None and not (
                bobs_session.exists() and 'sensors ...' in bobs_session.read_text()):
            time.sleep(0.1)
        assert proc.poll() is None, proc.stdout.read()
        # What a killed class grade keeps: alice's result, written as she finished.
        with open(out / 'grades.csv') as stream:
            assert stream.read().splitlines()[1].startswith('alice,pass,pass,pass,')
        proc.send_signal(signal.SIGTERM)
        output, _ = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, output
    assert 'stopped' in output
    with open(out / 'alice' / 'grade.json') as stream:
        alice = json.load(stream)
    assert all(item['passed'] for item in alice['items']), alice
    with open(out / 'bob' / 'grade.json') as stream:
        bob = json.load(stream)
    stopped = [item for item in bob['items'] if not item['passed']]
    assert stopped and all('the grade was stopped by SIGTERM during the rubric run' in item['evidence']
                           for item in stopped), bob['items']
    with open(out / 'summary.md') as stream:
        summary = stream.read()
    assert 'then stopped by SIGTERM' in summary, summary
    with open(tmp_path / 'all.json') as stream:
        assert [entry['name'] for entry in json.load(stream)['submissions']] == ['alice', 'bob']
    # Nothing of the grade runs on: no grader, session, master, launch or node of the class's.
    time.sleep(1.0)
    assert processes_mentioning(str(tmp_path)) == []
    match = re.search(r'as uid (\d+), a uid of its own', bob['isolation'])
    if match:
        assert processes_of_uid(int(match.group(1))) == []
