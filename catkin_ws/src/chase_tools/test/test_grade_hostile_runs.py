"""The grader against hostile submissions that need a grade of their own: a build that never
ends, a grade stopped by SIGTERM, a rubric run past --timeout-run, a machine without cgroups,
and a node that shuts the grader's node down.

As in test_grade_hostile.py, each test also checks that nothing outside the scratch folder
changed.
"""


import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402
from grade_support import processes_of_uid  # noqa: E402
from hostile_support import (GRADE_TIMEOUT_S, GRADER_MEMORY_BOUND, LIMITS,  # noqa: E402
                             NEEDS_ROOT_AND_BWRAP, REPORT_BOUND, SHUT_DOWN_GRADE_S, STOP_WAIT_S,
                             folder_size, grade, host, sandbox_uid, watched_grade)

pytestmark = NEEDS_ROOT_AND_BWRAP


def test_a_build_that_never_ends_stops_at_the_build_timeout(host, tmp_path):
    path = variants.compose('hostile_endless_build', tmp_path / 'submission', **host.params)
    proc = grade([path, '--timeout-build', '15', '--output', tmp_path / 'report'])
    assert proc.returncode == 1, proc.stdout
    with open(tmp_path / 'report' / 'grade.json') as stream:
        result = json.load(stream)
    builds = result['items'][0]
    assert not builds['passed']
    assert 'the build did not finish within 15 s (--timeout-build)' in builds['evidence'], builds
    assert processes_of_uid(sandbox_uid(result)) == []
    host.assert_unchanged()


def test_a_stopped_grade_writes_its_report_and_leaves_nothing_running(host, tmp_path):
    path = variants.compose('hostile_endless_build', tmp_path / 'submission', **host.params)
    proc = subprocess.Popen(['grade', path, '--output', str(tmp_path / 'report'),
                             '--json', str(tmp_path / 'grade.json')],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines, building = [], threading.Event()

    def read():
        for line in proc.stdout:
            lines.append(line)
            if line.startswith('grade: building'):
                building.set()
    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        building.wait(STOP_WAIT_S)
        proc.send_signal(signal.SIGTERM)
        proc.wait(STOP_WAIT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    reader.join(10)
    output = ''.join(lines)
    assert proc.returncode == 130, output
    for written in (tmp_path / 'grade.json', tmp_path / 'report' / 'grade.json'):
        with open(written) as stream:
            result = json.load(stream)
        assert [item['passed'] for item in result['items']] == [False] * 7
        assert result['items'][0]['evidence'] == \
            'not finished: the grade was stopped by SIGTERM during the build'
    with open(tmp_path / 'report' / 'report.md') as stream:
        assert 'the grade was stopped by SIGTERM during the build' in stream.read()
    assert processes_of_uid(sandbox_uid(result)) == []
    pids = '/sys/fs/cgroup/pids'
    assert not os.path.isdir(pids) or 'grade_%d' % proc.pid not in os.listdir(pids)
    assert building.is_set(), output          # it was stopped while it built
    host.assert_unchanged()


def test_a_rubric_run_past_timeout_run_is_stopped_and_the_report_names_the_step(host, tmp_path):
    """The dripping service again, with --timeout-run shorter than the grader's wait for drive_bot:
    the run is stopped, the report says at which step, and nothing of the submission runs on.
    Graded as a class of one, so that the option is passed on to the submission's grade."""
    folder = tmp_path / 'class'
    variants.compose('hostile_drips_service', folder, **host.params)
    proc = grade([folder, '--class', '--trials', '0', '--timeout-run', '20', '--output',
                  tmp_path / 'report'] + LIMITS, timeout=STOP_WAIT_S * 5)
    assert proc.returncode == 1, proc.stdout
    with open(tmp_path / 'report' / 'hostile_drips_service' / 'grade.json') as stream:
        result = json.load(stream)
    said = '\n'.join(result['notes'])
    assert ('the rubric run did not finish within 20 s (--timeout-run), so it was stopped; the items '
            'not yet graded are failed') in said, said
    step = re.search(r'^the step (.+) of the rubric run did not finish: the grade was stopped at the '
                     r'time limit of the rubric run \(20 s, --timeout-run\) while it ran$', said, re.M)
    assert step, said
    evidence = {item['name']: item['evidence'] for item in result['items']}
    assert evidence['chase'] == ('not run: the grade was stopped at the time limit of the rubric run '
                                 '(20 s, --timeout-run)'), evidence
    with open(tmp_path / 'report' / 'hostile_drips_service' / 'report.md') as stream:
        assert 'did not finish: the grade was stopped at the time limit' in stream.read()
    assert processes_of_uid(sandbox_uid(result)) == []
    host.assert_unchanged()


def test_without_a_cgroup_the_address_space_limit_leaves_the_simulator_running(host, tmp_path):
    """The fallback where no cgroup v1 memory hierarchy can be used, forced by hiding
    /sys/fs/cgroup from the grader (a bwrap of root's that shows it the rest of the machine as
    it is): memory is bounded per process by address space, which must leave room for what the
    simulator in the submission's sandbox reserves, or it cannot start its threads under a
    --memory-limit of 768M."""
    path = variants.compose('py_correct', tmp_path / 'submission')
    proc = subprocess.run([shutil.which('bwrap'), '--dev-bind', '/', '/', '--tmpfs', '/sys/fs/cgroup',
                           'grade', path, '--trials', '0', '--memory-limit', '768M',
                           '--output', str(tmp_path / 'report')],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=GRADE_TIMEOUT_S, check=False)
    with open(tmp_path / 'report' / 'grade.json') as stream:
        result = json.load(stream)
    # Why there is no cgroup depends on the machine: no cgroup v2 mount, or one whose controllers
    # are cgroup v1's.
    assert re.search(r'limits without a cgroup \((no cgroup v1 memory hierarchy, and no cgroup v2 one '
                     r'here|cgroup v2 does not give the grader\'s cgroup \S+ the memory and pids '
                     r'controllers [^)]*\))\): 2\.8 GiB of address space per process \(the memory limit '
                     r'of 768 MiB and 2 GiB that processes reserve but do not use\)',
                     result['isolation']), result['isolation']
    evidence = {item['name']: item for item in result['items']}
    for name in ('world_launches', 'sensors', 'drive_bot_service'):
        assert evidence[name]['passed'], (name, evidence[name]['evidence'], proc.stdout[-2000:])
    assert processes_of_uid(sandbox_uid(result)) == []


def test_a_node_that_shuts_the_graders_node_down_ends_the_run_at_once_with_that_reason(host, tmp_path):
    """In the one trial, a node calls shutdown on the grader's node over XML-RPC: the run ends
    then, within SHUT_DOWN_GRADE_S, rather than waiting out the trial's time for a clock the
    node no longer hears."""
    name = 'hostile_shuts_down_grader'
    path = variants.compose(name, tmp_path / 'submission', **host.params)
    report = tmp_path / 'report'
    proc, watch = watched_grade([path, '--trials', '1', '--output', report] + LIMITS,
                                timeout=SHUT_DOWN_GRADE_S)
    assert proc.returncode == 1, proc.stdout
    with open(report / 'grade.json') as stream:
        result = json.load(stream)
    with open(report / 'logs' / 'ball_chaser_launch.log', errors='replace') as stream:
        assert 'SHUT DOWN /grade_probe' in stream.read()
    chase = {item['name']: item for item in result['items']}['chase']
    assert not chase['passed']
    assert re.match(r"not run: the grader's node /grade_probe was shut down \(external shutdown "
                    r"request from \[/hostile\]: \[hostile\]\)$", chase['evidence']), chase
    # In its trial, or, when the trial was over by then, as the robot is tested for a stop.
    assert re.search(r"^the run ended during (chase|stops_without_ball): the grader's node "
                     r"/grade_probe was shut down \(external shutdown request", '\n'.join(result['notes']),
                     re.M), result['notes']
    assert folder_size(report) < REPORT_BOUND
    assert 0 < watch.peaks[''] < GRADER_MEMORY_BOUND, watch.peaks
    host.assert_unchanged()
