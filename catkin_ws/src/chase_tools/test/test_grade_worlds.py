"""Trials shared among parallel worlds come out as they do in one world.

One submission whose robot stops short of the ball, so that each trial runs to
its time limit (two minutes of sim time) and the extra world, which starts
after the first has chased for a few seconds, is up in time to take the
second, is graded twice with two trials: with --worlds 1 and with --worlds 2. The placements, the
outcomes, the reasons (their figures to a last digit) and the figures behind them
must match trial by trial.

A world's physics is not bit for bit another's (their histories before the
first reset differ): a turn summed over a minute of small corrections can
differ in its third decimal, so the figures are compared to the centimetre
and the hundredth of a radian. Commands and calls are counted up to the end
of the trial by the grader's clock, which can put the last one on either side
of it: they may differ by one.
"""
import os
import re

import pytest

from chase_tools.grading import sandbox
from grade_support import grade_variants, items

GRADED = 'py_stops_far'
# Figures of a trial's record compared to within this much; every other field exactly. The time
# since which the robot stayed within 2 cm and 0.05 rad of its last pose follows its last slow
# correction: at 0.1 rad/s the 0.01 rad that a turn may differ by moves it by 0.1 s.
CLOSE = {'closest': 0.01, 'gap_at_end': 0.01, 'moved_m': 0.01, 'turned_rad': 0.01, 'stopped_at': 0.15,
         'time_to_ball': 0.021, 'left_view_at': 0.05}
COUNTS = ('commands', 'moving_commands', 'calls', 'moving_calls')
FIGURE = re.compile(r'\d+\.\d+')

pytestmark = pytest.mark.skipif(sandbox.check() is not None,
                                reason='the grader needs bubblewrap: %s' % sandbox.check())


@pytest.fixture(scope='module')
def graded(tmp_path_factory):
    """{worlds: (the grade process, its JSON, the report folder)}."""
    runs = {}
    for worlds in (1, 2):
        proc, results, report = grade_variants(tmp_path_factory, [GRADED], trials=2, timeout=120,
                                               options=['--worlds', str(worlds)])
        runs[worlds] = (proc, results[GRADED], report / GRADED)
    return runs


def test_two_worlds_share_the_trials_each_with_its_own_logs(graded):
    proc, result, report = graded[2]
    assert [trial['world'] for trial in result['trials']] == [1, 2], proc.stdout
    assert result['worlds'] == 2
    assert 'Wall time:' in (report / 'report.md').read_text()
    assert 'the trials were shared among 2 worlds' in (report / 'report.md').read_text()
    for log in ('world_launch.log', 'ball_chaser_launch.log', 'roscore.log', 'session.log'):
        assert os.path.getsize(report / 'logs' / 'world_2' / log) > 0, log
    for trial in result['trials']:
        assert (report / trial['png']).is_file()
    assert [trial['world'] for trial in graded[1][1]['trials']] == [1, 1]
    assert graded[1][1]['worlds'] == 1


def test_each_trial_comes_out_the_same_in_one_world_and_in_two(graded):
    alone, shared = graded[1][1]['trials'], graded[2][1]['trials']
    assert len(alone) == len(shared) == 2
    for one, two in zip(alone, shared):
        for field in ('index', 'robot', 'ball', 'reached', 'error'):
            assert one[field] == two[field], (field, one, two)
        # The reason's words alike; its figures are the record's, rounded, so one that lies
        # near a rounding boundary may differ by a last digit.
        assert FIGURE.sub('#', one['reason']) == FIGURE.sub('#', two['reason']), (one, two)
        assert [float(x) for x in FIGURE.findall(one['reason'])] == pytest.approx(
            [float(x) for x in FIGURE.findall(two['reason'])], abs=0.1 + 1e-9), (one, two)
        assert not one['reached'] and one['reason'].startswith('stopped short')
        assert one['closest'] == pytest.approx(two['closest'], abs=CLOSE['closest'])
        assert set(one['record']) == set(two['record'])
        for name, value in one['record'].items():
            if name in CLOSE:
                assert value == pytest.approx(two['record'][name], abs=CLOSE[name]), (name, one, two)
            elif name in COUNTS:
                assert abs(value - two['record'][name]) <= 1, (name, one, two)
            else:
                assert value == two['record'][name], (name, one, two)


def test_process_images_calls_are_counted_in_every_world(graded):
    for _proc, result, _report in graded.values():
        calls = items({GRADED: result}, GRADED)['process_image_calls']
        assert calls['passed'], calls['evidence']
        during = int(calls['evidence'].split(' during the chase trials')[0].rsplit('(', 1)[1])
        # Each trial's own count stops at its end; the world went on until it was paused.
        assert during >= sum(trial['record']['calls'] for trial in result['trials']) > 0
    verdicts = {worlds: {item['name']: item['passed'] for item in result['items']}
                for worlds, (_proc, result, _report) in graded.items()}
    assert verdicts[1] == verdicts[2]
