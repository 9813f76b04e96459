"""grade FOLDER --slurm on a real one-node Slurm cluster of this machine (slurm_cluster.py),
checked against the same folder graded locally, and grade --gather on what they leave.

The class is cheap: a correct Python submission (one trial), one whose
CMakeLists has a typo (its configure fails at once) and a folder without
packages (nothing to build).
"""
import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys

import pytest

from chase_tools.grading import gather, sandbox, slurm

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import slurm_cluster  # noqa: E402
import variants  # noqa: E402

CLASS = ('nothing_here', 'py_cmake_typo', 'py_correct')
# The options a teacher would give; the README shows the same command.
SBATCH_OPTIONS = ['--partition=%s' % slurm_cluster.PARTITION, '--time=00:20:00', '--mem=4G']
CHEAP = ['--trials', '1', '--timeout', '30']
GRADE_TIMEOUT_S = 900

pytestmark = [
    pytest.mark.skipif(sandbox.check() is not None,
                       reason='the grader needs bubblewrap: %s' % sandbox.check()),
    pytest.mark.skipif(slurm_cluster.why_unavailable() is not None,
                       reason='no Slurm here: %s' % slurm_cluster.why_unavailable()),
]


def run(cmd, env=None, timeout=GRADE_TIMEOUT_S):
    return subprocess.run([str(part) for part in cmd], env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=timeout, check=False)


@pytest.fixture(scope='module')
def class_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp('class')
    for name in ('py_correct', 'py_cmake_typo'):
        variants.compose(name, folder)
    (folder / 'nothing_here').mkdir()
    (folder / 'nothing_here' / 'README.md').write_text('I forgot to push my packages.\n')
    return folder


@pytest.fixture(scope='module')
def cluster():
    with slurm_cluster.SlurmCluster() as started:
        yield started


@pytest.fixture(scope='module')
def graded(class_folder, cluster, tmp_path_factory):
    """The two runs' (CompletedProcess, report folder, --json), by 'slurm' and 'local'."""
    out = tmp_path_factory.mktemp('graded')
    runs = {}
    runs['slurm'] = run(['grade', class_folder, '--class', '--output', out / 'slurm',
                         '--json', out / 'slurm.json']
                        + CHEAP + ['--slurm'] + SBATCH_OPTIONS + ['--job-name=go-chase-it'],
                        env=cluster.env())
    runs['local'] = run(['grade', class_folder, '--class', '--output', out / 'local',
                         '--json', out / 'local.json',
                         '--jobs', '2'] + CHEAP)
    return {how: (proc, out / how, out / ('%s.json' % how)) for how, proc in runs.items()}


def read(path):
    with open(path) as stream:
        return stream.read()


def csv_rows(report):
    """grades.csv's rows by submission, but how long each took."""
    with open(os.path.join(report, 'grades.csv'), newline='') as stream:
        return {row['submission']: {column: value for column, value in row.items()
                                    if column not in dict(gather.WALL_TIME_COLUMNS)}
                for row in csv.DictReader(stream)}


def table(report):
    """summary.md's lines but the one that says how and how fast the class was graded, and
    its last column, how long each took."""
    return [re.sub(r' [^|]*\|$', '', line) if line.startswith('|') else line
            for line in read(os.path.join(report, 'summary.md')).splitlines()
            if line and not line.startswith('Graded ')]


def verdicts(json_path):
    with open(json_path) as stream:
        return {entry['name']: {item['name']: item['passed'] for item in entry['items']}
                for entry in json.load(stream)['submissions']}


def test_each_submission_is_one_array_task(graded, cluster, monkeypatch):
    monkeypatch.setenv('SLURM_CONF', cluster.env()['SLURM_CONF'])
    proc, report, _json = graded['slurm']
    assert proc.returncode == 1, proc.stdout + proc.stderr       # two submissions fail items
    assert 'grade: 3 submissions as Slurm array job' in proc.stdout, proc.stdout + proc.stderr
    assert 'py_correct                     7/7 items, chase 1/1' in proc.stdout
    for index, name in enumerate(CLASS):
        task_log = read(os.path.join(report, 'slurm', 'task_%d.log' % index))
        # The teacher's --job-name overrides the script's own default.
        assert 'grade: %s in Slurm task ' % name in task_log and '(job go-chase-it)' in task_log, task_log
        assert os.path.isfile(os.path.join(report, name, 'report.md'))
    assert 'Graded as Slurm array job' in read(os.path.join(report, 'summary.md'))
    # Every submission was graded, so every task succeeded, those that failed items too.
    job_id = proc.stdout.split('array job ')[1].split()[0]
    states = slurm.final_states(job_id)
    assert states == {index: 'COMPLETED (exit 0:0)' for index in range(len(CLASS))}, states


def test_slurm_and_a_local_grade_gather_the_same_class(graded):
    slurm_report, local_report = graded['slurm'][1], graded['local'][1]
    rows = csv_rows(slurm_report)
    assert sorted(rows) == sorted(CLASS)
    assert rows == csv_rows(local_report)
    assert table(slurm_report) == table(local_report)
    assert verdicts(graded['slurm'][2]) == verdicts(graded['local'][2])
    correct = rows['py_correct']
    assert [correct[item] for item in ('builds', 'chase', 'chase_reached', 'chase_trials', 'success_rate')] \
        == ['pass', 'pass', '1', '1', '1']
    typo = rows['py_cmake_typo']
    assert typo['builds'] == 'fail' and typo['chase_trials'] == '0'
    assert typo['notes'].startswith('builds: packages ball_chaser, my_robot: CMake configuration failed')
    assert 'not run (the build failed): world_launches' in typo['notes']


def test_gather_rebuilds_the_summary_and_the_csv(graded, tmp_path):
    report = tmp_path / 'class-report'
    shutil.copytree(graded['slurm'][1], report)
    expected_csv = read(report / 'grades.csv')
    os.remove(report / 'grades.csv')
    os.remove(report / 'summary.md')
    proc = run(['grade', '--gather', report])
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert read(report / 'grades.csv') == expected_csv
    assert table(report) == table(graded['slurm'][1])


def test_a_missing_or_broken_grade_json_is_a_row_that_says_so(graded, tmp_path):
    report = tmp_path / 'class-report'
    shutil.copytree(graded['local'][1], report)
    os.remove(report / 'py_correct' / 'grade.json')
    (report / 'py_cmake_typo' / 'grade.json').write_text('{"items": [')
    proc = run(['grade', '--gather', report, '--json', tmp_path / 'all.json'])
    assert proc.returncode == 1, proc.stdout + proc.stderr
    rows = csv_rows(report)
    assert rows['py_correct']['builds'] == '' and rows['py_correct']['notes'] == (
        'not graded: no grade.json: the grader did not finish; see py_correct/grade.log')
    assert rows['py_cmake_typo']['notes'].startswith(
        'not graded: py_cmake_typo/grade.json cannot be read: ')
    assert rows['nothing_here']['builds'] == 'fail'
    assert '| [py_correct](py_correct/grade.log) | not graded: no grade.json' in read(report / 'summary.md')
    entries = {entry['name']: entry for entry in json.loads(read(tmp_path / 'all.json'))['submissions']}
    assert entries['py_correct']['items'][0]['evidence'].startswith('not run: no grade.json')


def test_sbatch_options_grade_cannot_pass_on_are_a_clear_error(class_folder, cluster, tmp_path):
    refused = run(['grade', class_folder, '--output', tmp_path / 'a', '--slurm', '--no-such-option'],
                  env=cluster.env(), timeout=120)
    assert refused.returncode == 2
    assert refused.stderr.startswith('grade: sbatch refused the job (exit '), refused.stderr
    assert "sbatch: unrecognized option '--no-such-option'" in refused.stderr
    own = run(['grade', class_folder, '--output', tmp_path / 'b', '--slurm', '--array=0-1'],
              env=cluster.env(), timeout=120)
    assert own.returncode == 2
    assert 'grade: --array=0-1: grade makes the array itself' in own.stderr, own.stderr
    assert cluster.jobs() == []


def test_ctrl_c_cancels_the_array_and_gathers_what_it_left(class_folder, cluster, tmp_path):
    report = tmp_path / 'class-report'
    # Held, the tasks stay pending: nothing is graded before the interrupt.
    proc = subprocess.Popen(['grade', str(class_folder), '--output', str(report), '--slurm', '--hold'],
                            env=cluster.env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
    try:
        first = proc.stdout.readline()
        assert 'as Slurm array job' in first, first + proc.stdout.read()
        job_id = first.split('array job ')[1].split()[0]
        assert sorted(cluster.jobs()) == ['%s_%d' % (job_id, index) for index in range(len(CLASS))]
        proc.send_signal(signal.SIGINT)
        rest = proc.communicate(timeout=180)[0]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, rest
    assert 'grade: cancelling Slurm job %s' % job_id in rest
    assert cluster.jobs() == []
    summary = read(report / 'summary.md')
    assert 'Cancelled Slurm array job %s.' % job_id in summary
    gathered = run(['grade', '--gather', report])
    assert gathered.returncode == 1
    assert [line.split()[0] for line in gathered.stdout.splitlines()[:-1]] == list(CLASS)
    for index, name in enumerate(CLASS):
        assert ('| [%s](%s/grade.log) | not graded: no grade.json: Slurm task %s_%d ended CANCELLED '
                '(exit 0:0); see %s/grade.log |' % (name, name, job_id, index, name)) in summary, summary
        assert read(report / name / 'grade.log') == 'grade: waiting for Slurm task %s_%d to grade %s\n' % (
            job_id, index, class_folder / name)
