"""The class-scale grader's pure parts: gathering grade.json files into the summary and the
CSV, Gradescope's format, and grade --slurm's arguments, script and reading of Slurm's answers.
No master, no Slurm."""
import csv
import json
import os
import subprocess

import jsonschema
import pytest

from chase_tools.grading import cli, formats, gather, rubric, slurm

HERE = os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(HERE, 'fixtures', 'gradescope_results.schema.json')) as _stream:
    GRADESCOPE_SCHEMA = json.load(_stream)


def a_grade(failing=(), trials=((True, 4.2), (False, None))):
    grade = rubric.Grade('/class/alice', seed=3, reach=0.15)
    for name in rubric.ITEM_NAMES:
        if name in failing:
            grade.set(name, False, failing[name], ['  log line one', '  log line two'])
        else:
            grade.set(name, True, '%s was fine' % name)
    for index, (reached, seconds) in enumerate(trials):
        grade.trials.append(rubric.Trial(index, [0.5, -1.0, 1.57], [1.5, 0.25], reached=reached,
                                         time_to_ball=seconds, closest=0.12 if reached else 0.93,
                                         reason='pushed the ball' if reached else 'turned away: ...'))
    return grade


def write_grade(report_dir, name, grade):
    os.makedirs(os.path.join(report_dir, name), exist_ok=True)
    rubric.write_json(grade, os.path.join(report_dir, name, gather.GRADE_FILE))


def csv_rows(report_dir):
    with open(os.path.join(report_dir, gather.CSV_FILE), newline='') as stream:
        return list(csv.DictReader(stream))


# -- gathering -----------------------------------------------------------------------------

def test_the_csv_has_one_column_per_item_and_the_failures_on_one_line(tmp_path):
    alice = a_grade()
    alice.wall_time = {'total': 14.2, 'build': 3.1, 'rubric_run': 10.5}
    write_grade(tmp_path, 'alice', alice)
    failing = {'drive_bot_service': 'the service has type x, "quoted", not the course\'s',
               'chase': 'not run: the world did not launch',
               'stops_without_ball': 'not run: the world did not launch'}
    write_grade(tmp_path, 'bob', a_grade(failing, trials=()))
    gather.write(str(tmp_path), gather.read_all(str(tmp_path), ['alice', 'bob']))
    alice, bob = csv_rows(tmp_path)
    assert list(alice) == list(gather.CSV_COLUMNS)
    assert [alice[name] for name in rubric.ITEM_NAMES] == ['pass'] * len(rubric.ITEM_NAMES)
    assert (alice['chase_reached'], alice['chase_trials'], alice['success_rate']) == ('1', '2', '0.5')
    assert (alice['total_s'], alice['build_s'], alice['rubric_run_s']) == ('14.2', '3.1', '10.5')
    assert alice['report'] == 'alice/report.md' and alice['notes'] == ''
    assert bob['drive_bot_service'] == 'fail' and bob['builds'] == 'pass' and bob['total_s'] == ''
    assert bob['notes'] == ('drive_bot_service: the service has type x, "quoted", not the course\'s'
                            ' | not run (the world did not launch): stops_without_ball, chase')


def test_a_cell_a_spreadsheet_would_run_as_a_formula_is_kept_as_text():
    assert gather.csv_safe('=HYPERLINK("http://x", "y")') == '\'=HYPERLINK("http://x", "y")'
    assert gather.csv_safe('-2+3') == "'-2+3"
    assert gather.csv_safe('@SUM(A1)') == "'@SUM(A1)"
    assert gather.csv_safe('line one\nline\ttwo\r') == 'line one line two '
    assert gather.csv_safe('builds: fine, really') == 'builds: fine, really'


def test_evidence_from_a_submission_cannot_break_the_csv(tmp_path):
    write_grade(tmp_path, 'mallory', a_grade({'builds': '=cmd|\' /C calc\'!A0\r\n,"x"'}))
    gather.write(str(tmp_path), gather.read_all(str(tmp_path), ['mallory']))
    with open(tmp_path / gather.CSV_FILE, newline='') as stream:
        rows = list(csv.reader(stream))
    assert len(rows) == 2 and len(rows[1]) == len(gather.CSV_COLUMNS)
    assert rows[1][-1].startswith('builds: =cmd')        # not at the start of its cell
    assert '\n' not in rows[1][-1] and '\r' not in rows[1][-1]


def test_a_missing_or_unreadable_grade_is_a_row_that_says_so(tmp_path):
    write_grade(tmp_path, 'alice', a_grade())
    os.makedirs(tmp_path / 'bob')
    (tmp_path / 'bob' / gather.LOG_FILE).write_text('Traceback ...\n')
    os.makedirs(tmp_path / 'carol')
    (tmp_path / 'carol' / gather.GRADE_FILE).write_text('["not", "a", "grade"]')
    os.makedirs(tmp_path / 'dave')
    (tmp_path / 'dave' / gather.GRADE_FILE).write_text('{"items": [{"name": "builds"}]}')
    os.makedirs(tmp_path / 'erin')
    (tmp_path / 'erin' / gather.GRADE_FILE).write_text('{"items": ')
    assert gather.names_in(str(tmp_path)) == ['alice', 'bob', 'carol', 'dave', 'erin']
    rows = gather.read_all(str(tmp_path), gather.names_in(str(tmp_path)) + ['frank'],
                           {'frank': 'Slurm task 7_5 ended TIMEOUT (exit 0:15)'})
    problems = {row.name: row.problem for row in rows}
    assert problems['alice'] == ''
    assert problems['bob'] == 'no grade.json: the grader did not finish; see bob/grade.log'
    assert problems['carol'].startswith('carol/grade.json is not a grade: ')
    assert problems['dave'].startswith('dave/grade.json is not a grade: ')
    assert problems['erin'].startswith('erin/grade.json cannot be read: ')
    assert problems['frank'] == 'no grade.json: Slurm task 7_5 ended TIMEOUT (exit 0:15)'
    assert not gather.passed(rows)
    summary = gather.summary_markdown(rows)
    assert '1 graded, 1 of them passed every item; 5 not graded.' in summary
    assert '| [bob](bob/grade.log) | not graded: no grade.json: the grader did not finish' in summary
    assert '| frank | not graded: no grade.json: Slurm task 7_5 ended TIMEOUT (exit 0:15) |' in summary
    entries = gather.folder_json(rows, {'frank': '/class/frank'})['submissions']
    assert entries[-1]['submission'] == '/class/frank' and entries[-1]['name'] == 'frank'
    assert [item['evidence'] for item in entries[-1]['items']] == [
        'not run: no grade.json: Slurm task 7_5 ended TIMEOUT (exit 0:15)'] * len(rubric.ITEM_NAMES)


def test_the_summary_links_each_report_and_counts_the_class(tmp_path):
    alice = a_grade()
    alice.wall_time = {'total': 14.2, 'build': 3.1, 'rubric_run': 10.5}
    write_grade(tmp_path, 'alice', alice)
    write_grade(tmp_path, 'bob', a_grade({'chase': 'reached 1 of 2 trials'}))
    rows = gather.read_all(str(tmp_path), ['alice', 'bob'])
    summary = gather.summary_markdown(rows, 'Graded 2 at a time in 60 s.')
    lines = summary.splitlines()
    assert lines[:4] == ['# Go Chase It: 2 submissions', '', 'Graded 2 at a time in 60 s.', '']
    assert '2 graded, 1 of them passed every item.' in lines
    assert ('| [alice](alice/report.md) | 7 passed, 0 failed, 0 not judged | PASS | PASS | PASS | PASS '
            '| PASS | PASS | PASS 1/2 | 14.2 s (build 3.1 s, rubric run 10.5 s) |') in lines
    # A grade.json written before the grader timed itself has no time to show.
    assert ('| [bob](bob/report.md) | 6 passed, 1 failed, 0 not judged | PASS | PASS | PASS | PASS '
            '| PASS | PASS | **FAIL** 1/2 |  |') in lines


def not_judged_grade():
    """A grade with each verdict: chase failed, process_image_calls not judged."""
    grade = a_grade({'chase': 'reached 0 of 2 trials'}, trials=((False, None), (False, None)))
    grade.not_judged('process_image_calls', 'no chase trial ran, so /process_image never saw the ball')
    return grade


def test_a_not_judged_item_is_counted_apart_from_the_failures_in_the_summary_and_the_csv(tmp_path):
    write_grade(tmp_path, 'alice', not_judged_grade())
    rows = gather.read_all(str(tmp_path), ['alice'])
    gather.write(str(tmp_path), rows)
    summary = (tmp_path / gather.SUMMARY_FILE).read_text().splitlines()
    assert ('| [alice](alice/report.md) | 5 passed, 1 failed, 1 not judged | PASS | PASS | PASS '
            '| PASS | *NOT JUDGED* | PASS | **FAIL** 0/2 |  |') in summary
    assert any(line.startswith('1 graded, 0 of them passed every item; 1 with items not judged')
               for line in summary), summary
    (alice,) = csv_rows(tmp_path)
    assert alice['process_image_calls'] == 'not judged' and alice['chase'] == 'fail'
    assert gather.row_line(rows[0]) == ('5/7 items (1 failed, 1 not judged), chase 0/2; failed: chase; '
                                        'not judged: process_image_calls')


# -- Gradescope ----------------------------------------------------------------------------

def test_gradescope_results_have_one_test_per_item_in_gradescopes_format():
    results = formats.gradescope(a_grade({'sensors': 'no image on /camera/rgb/image_raw'}), 61.4)
    jsonschema.validate(results, GRADESCOPE_SCHEMA)
    assert [test['name'] for test in results['tests']] == list(rubric.ITEM_NAMES)
    assert [test['number'] for test in results['tests']] == ['1', '2', '3', '4', '5', '6', '7']
    sensors = results['tests'][2]
    assert (sensors['score'], sensors['max_score'], sensors['status']) == (0.0, 1.0, 'failed')
    assert sensors['output'] == ('%s.\n\nno image on /camera/rgb/image_raw\n  log line one\n'
                                 '  log line two' % rubric.DESCRIPTIONS['sensors'])
    assert results['score'] == 6.0 and results['execution_time'] == 61
    # The grader's own output is for the staff.
    assert results['stdout_visibility'] == 'hidden'
    chase = results['tests'][-1]['output'].splitlines()
    assert chase[-2:] == ['trial 0: robot at (0.50, -1.00, 1.57), ball at (1.50, 0.25): reached the ball in 4.2 s '
                          '(pushed the ball)',
                          'trial 1: robot at (0.50, -1.00, 1.57), ball at (1.50, 0.25): did not reach the ball: '
                          'turned away: ... (closest 0.93 m of its surface)']


def test_an_item_with_no_result_is_a_failed_test():
    grade = rubric.Grade('/class/alice')
    results = formats.gradescope(grade)
    jsonschema.validate(results, GRADESCOPE_SCHEMA)
    assert results['score'] == 0 and 'execution_time' not in results
    assert all(test['status'] == 'failed' and test['output'].endswith('not run')
               for test in results['tests'])


def test_gradescope_says_a_not_judged_test_was_not_judged_and_scores_it_nothing():
    results = formats.gradescope(not_judged_grade())
    jsonschema.validate(results, GRADESCOPE_SCHEMA)
    tests = {test['name']: test for test in results['tests']}
    unseen, chase = tests['process_image_calls'], tests['chase']
    assert (unseen['score'], unseen['status'], unseen['tags']) == (0.0, 'failed', ['not judged'])
    assert unseen['extra_data'] == {'verdict': 'not judged'}
    assert unseen['output'].startswith('NOT JUDGED: the grader could not observe this item')
    assert unseen['output'].endswith('not judged: no chase trial ran, so /process_image never saw the ball')
    # A failure is only a failure.
    assert 'tags' not in chase and not chase['output'].startswith('NOT JUDGED')
    assert results['output'].startswith('Go Chase It rubric: 5 of 7 items passed, 1 failed, 1 not judged.')


def test_format_gradescope_is_for_one_submission(tmp_path, capsys):
    for extra in (['--slurm'], ['--gather']):
        with pytest.raises(SystemExit) as stopped:
            cli.parse_args([str(tmp_path), '--format', 'gradescope'] + extra)
        assert stopped.value.code == 2
        assert '--format gradescope writes one submission\'s result' in capsys.readouterr().err


# -- Slurm ---------------------------------------------------------------------------------

@pytest.mark.parametrize('argv, grade_args, sbatch_options', [
    (['class', '--trials', '5'], ['class', '--trials', '5'], []),
    (['class', '--slurm'], ['class', '--slurm'], []),
    (['class', '--slurm', '--partition=teach', '-t', '20', '--', '--trials', '5'],
     ['class', '--slurm', '--trials', '5'], ['--partition=teach', '-t', '20']),
    (['class', '--output', 'out', '--slurm', '--qos', 'short'],
     ['class', '--output', 'out', '--slurm'], ['--qos', 'short']),
])
def test_everything_after_slurm_up_to_a_lone_dash_dash_goes_to_sbatch(argv, grade_args, sbatch_options):
    assert slurm.split_argv(argv) == (grade_args, sbatch_options)


def test_sbatch_options_that_grade_sets_itself_are_refused():
    for option in ('--array=1-3', '-a', '-a1-3', '--wrap=true'):
        assert 'grade makes the array itself' in slurm.check_options(['--time=5', option]), option
    assert slurm.check_options(['--account=teach', '-A', 'teach', '--mem=4G', '--parsable']) is None


def test_the_batch_script_enters_the_checkouts_environment_and_runs_one_task(tmp_path):
    script = slurm.write_job(str(tmp_path), ['alice', 'bob'], ['/class/alice', '/class/b b'],
                             ['--trials', '3'], '/opt/go chase')
    text = open(script).read().splitlines()
    assert text[:5] == ['#!/bin/bash', '#SBATCH --job-name=grade', '#SBATCH --cpus-per-task=2',
                        '#SBATCH --signal=B:TERM@120',
                        '#SBATCH --output=%s/slurm/task_%%a.log' % tmp_path]
    assert "if ! source '/opt/go chase/env.sh'; then" in text
    assert text[-1] == 'exec python -m chase_tools.grading.slurm %s/slurm/job.json' % tmp_path
    job = json.loads((tmp_path / 'slurm' / 'job.json').read_text())
    assert job['submissions'][1] == {'name': 'bob', 'path': '/class/b b'}
    assert job['grade_args'] == ['--trials', '3']
    assert os.path.isdir(tmp_path / 'alice') and os.path.isdir(tmp_path / 'bob')


def test_the_checkout_is_found_from_the_module():
    top = slurm.checkout_top()
    assert os.path.isfile(os.path.join(top, 'env.sh'))
    assert os.path.realpath(__file__).startswith(top + os.sep)


def answer(stdout='', stderr='', returncode=0):
    return subprocess.CompletedProcess([], returncode, stdout, stderr)


def test_task_states_come_from_scontrol_also_for_tasks_that_never_started(monkeypatch):
    lines = ['JobId=12 ArrayJobId=12 ArrayTaskId=0-2,4 JobName=grade JobState=CANCELLED '
             'Reason=JobHeldUser ExitCode=0:0',
             'JobId=15 ArrayJobId=12 ArrayTaskId=3 JobName=grade JobState=TIMEOUT Reason=TimeLimit '
             'ExitCode=0:15']
    monkeypatch.setattr(slurm, 'run', lambda cmd, timeout=60: answer('\n'.join(lines)))
    states = slurm.final_states('12')
    assert states == {0: 'CANCELLED (exit 0:0)', 1: 'CANCELLED (exit 0:0)', 2: 'CANCELLED (exit 0:0)',
                      3: 'TIMEOUT (exit 0:15)', 4: 'CANCELLED (exit 0:0)'}
    assert slurm.task_indices('0-10:5%2') == [0, 5, 10]


def test_a_job_squeue_has_forgotten_is_over_but_a_failing_squeue_is_not(monkeypatch):
    monkeypatch.setattr(slurm, 'run', lambda cmd, timeout=60: answer('3 RUNNING\n4 PENDING\n5 COMPLETED\n'))
    assert slurm.active_tasks('12') == {3: 'RUNNING', 4: 'PENDING'}
    monkeypatch.setattr(slurm, 'run', lambda cmd, timeout=60: answer(
        stderr='slurm_load_jobs error: Invalid job id specified', returncode=1))
    assert slurm.active_tasks('12') == {}
    monkeypatch.setattr(slurm, 'run', lambda cmd, timeout=60: answer(
        stderr='slurm_load_jobs error: Unable to contact slurm controller', returncode=1))
    assert slurm.active_tasks('12') is None

    def hangs(cmd, timeout=60):
        raise slurm.SlurmError('%s did not answer in %d s' % (cmd[0], timeout))
    monkeypatch.setattr(slurm, 'run', hangs)
    assert slurm.active_tasks('12') is None and slurm.final_states('12') == {}


def test_without_slurm_grade_says_so(monkeypatch, tmp_path):
    monkeypatch.setenv('PATH', str(tmp_path))
    with pytest.raises(slurm.SlurmError, match='sbatch is not installed here'):
        slurm.submit(str(tmp_path / 'grade.sbatch'), 2, [])


STOPPABLE = """
import signal, sys, time
def stop(signum, _frame):
    print('stopped by %s' % signal.Signals(signum).name, flush=True)
    sys.exit(130)
signal.signal(signal.SIGTERM, stop)
print('ready', flush=True)
time.sleep(60)
sys.exit(0)
"""


def test_a_slurm_task_passes_the_early_stop_signal_on_to_its_grade(tmp_path):
    """--signal=B:TERM@120 signals the batch script alone, which is the task's Python (exec):
    it must reach the grade it runs, which then writes its report before the time limit."""
    import signal as signals
    import sys
    import threading
    import time
    log_path = tmp_path / 'grade.log'

    def signal_when_ready():
        deadline = time.monotonic() + 30
        while 'ready' not in log_path.read_text() and time.monotonic() < deadline:
            time.sleep(0.05)
        os.kill(os.getpid(), signals.SIGTERM)     # as Slurm signals the batch script
    with open(log_path, 'w') as log:
        sender = threading.Thread(target=signal_when_ready)
        sender.start()
        status = slurm.run_passing_on_stops([sys.executable, '-c', STOPPABLE], log, dict(os.environ))
        sender.join(30)
    assert status == 130
    assert 'stopped by SIGTERM' in log_path.read_text()
    assert signals.getsignal(signals.SIGTERM) == signals.SIG_DFL


def test_json_into_a_missing_folder_makes_it_and_a_folder_is_refused(tmp_path, capsys):
    submission = tmp_path / 'alice'
    submission.mkdir()
    target = tmp_path / 'results' / 'deep' / 'grade.json'
    args = cli.parse_args([str(submission), '--json', str(target)])
    assert args.json == str(target) and target.parent.is_dir()
    with pytest.raises(SystemExit) as stop:
        cli.parse_args([str(submission), '--json', str(tmp_path)])
    assert stop.value.code == 2
    assert 'is a folder; give a file name in it' in capsys.readouterr().err
    blocked = tmp_path / 'a_file'
    blocked.write_text('')
    with pytest.raises(SystemExit):
        cli.parse_args([str(submission), '--json', str(blocked / 'grade.json')])
    assert 'cannot make its folder' in capsys.readouterr().err


def test_a_report_is_replaced_whole_or_not_at_all(tmp_path, monkeypatch):
    path = tmp_path / 'summary.md'
    path.write_text('the last whole summary\n')

    class Killed(BaseException):
        pass

    def dies_half_way(_text):
        raise Killed()
    real_fdopen = os.fdopen

    def fdopen(fd, *args, **kwargs):
        stream = real_fdopen(fd, *args, **kwargs)
        stream.write = dies_half_way
        return stream
    monkeypatch.setattr(os, 'fdopen', fdopen)
    with pytest.raises(Killed):
        rubric.write_whole(str(path), 'half of a new one')
    monkeypatch.undo()
    assert path.read_text() == 'the last whole summary\n'
    assert os.listdir(tmp_path) == ['summary.md']


# -- what a class grade passes on to each submission's grade ---------------------------------------

# Each option a submission's grade takes from the class grade, and a value other than its default.
PASSED_ON = {
    'trials': ['--trials', '5'], 'seed': ['--seed', '7'], 'worlds': ['--worlds', '2'],
    'timeout': ['--timeout', '42.5'], 'timeout_build': ['--timeout-build', '30'],
    'timeout_run': ['--timeout-run', '90'], 'reach': ['--reach', '0.3'], 'real_time': ['--real-time'],
    'pass_rate': ['--pass-rate', '0.55'], 'memory_limit': ['--memory-limit', '512M'],
    'process_limit': ['--process-limit', '300'], 'open_file_limit': ['--open-file-limit', '200'],
    'file_size_limit': ['--file-size-limit', '3M'], 'disk_limit': ['--disk-limit', '1G'],
    'log_limit': ['--log-limit', '64K'], 'scratch': ['--scratch', '/var/tmp/grade-scratch'],
    'keep_scratch': ['--keep-scratch'], 'rubric': ['--rubric', 'cpp_nodes,skid_steer'],
    'no_isolation': ['--no-isolation'], 'one': ['--one'],
}
# The class grade's own options, which each submission's grade has in its own way.
CLASS_OWN = {'path', 'output', 'json', 'format', 'slurm', 'gather', 'similar_to', 'similarity',
             'whole_class', 'jobs'}


def test_every_option_is_either_passed_on_or_the_class_grades_own():
    from chase_tools.grading import options
    dests = [option.dest for option in options.option_table()]
    assert len(dests) == len(set(dests))
    assert set(PASSED_ON) | CLASS_OWN == set(dests)
    assert not set(PASSED_ON) & CLASS_OWN


@pytest.mark.parametrize('cores', [None, 2])
def test_each_option_passed_on_comes_back_as_the_class_grade_parsed_it(tmp_path, cores):
    """parse the class grade's arguments, pass them on, parse them again: the same values."""
    from chase_tools.grading import options
    (tmp_path / 'alice').mkdir()
    defaults = cli.parse_args([str(tmp_path)])
    argv = [str(tmp_path), '--jobs', '3', '--output', str(tmp_path / 'out')]
    for words in PASSED_ON.values():
        argv += words
    args = cli.parse_args(argv)
    for dest in PASSED_ON:
        assert getattr(args, dest) != getattr(defaults, dest), dest     # each value says something
    forwarded = options.submission_args(args, cores)
    again = cli.parse_args([str(tmp_path / 'alice'), '--output', str(tmp_path / 'out' / 'alice')]
                           + forwarded)
    assert {dest: getattr(again, dest) for dest in PASSED_ON} == {
        dest: getattr(args, dest) for dest in PASSED_ON}
    # Each submission's grade is one submission, in its own folder.
    assert (again.jobs, again.whole_class) == (1, False)
    assert (again.json, again.similar_to, again.slurm) == ('', '', False)


def test_a_relative_scratch_is_passed_on_made_absolute(tmp_path, monkeypatch):
    from chase_tools.grading import options
    monkeypatch.chdir(tmp_path)
    args = cli.parse_args([str(tmp_path), '--scratch', 'scratch'])
    forwarded = options.submission_args(args)
    assert forwarded[forwarded.index('--scratch') + 1] == str(tmp_path / 'scratch')
