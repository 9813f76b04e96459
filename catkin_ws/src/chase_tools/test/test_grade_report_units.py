"""The report and its JSON from a submission's results. No master."""
import json
import math
import os

import pytest

from chase_tools.grading import rubric

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.realpath(os.path.join(HERE, '..', '..', '..', '..'))     # this workspace's checkout


# -- the report ----------------------------------------------------------------------------------

def test_the_json_names_every_item_in_order_even_when_the_run_stopped_early(tmp_path):
    grade = rubric.Grade('/sub', seed=3)
    grade.set('builds', False, 'catkin_make failed', ['  a.cpp:1: error: x'])
    grade.not_run('the build failed')
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    data = json.loads((tmp_path / 'g.json').read_text())
    assert [item['name'] for item in data['items']] == list(rubric.ITEM_NAMES)
    assert set(data['items'][0]) == {'name', 'passed', 'evidence', 'judged'}
    assert data['items'][0]['evidence'] == 'catkin_make failed\n  a.cpp:1: error: x'
    assert data['items'][3]['evidence'] == 'not run: the build failed'
    assert data['success_rate'] == 0.0 and data['trials'] == []
    assert {'builds', 'world_launches', 'sensors', 'drive_bot_service', 'process_image_calls',
            'stops_without_ball', 'chase'} <= {item['name'] for item in data['items']}


def test_the_markdown_has_one_line_per_item_and_the_log_lines_below():
    grade = rubric.Grade('/subs/alice', seed=1, reach=0.15)
    for name in rubric.ITEM_NAMES:
        grade.set(name, name != 'chase', 'evidence of %s' % name)
    grade.set('chase', False, '1 of 2 placements reached', ['  trial 1: sim time stalled'])
    grade.trials = [rubric.Trial(0, [0.0, 0.0, 0.5], [1.0, 1.0], True, 3.2, 0.12, 'trial_00.png',
                                 reason='came within 15 cm of the ball\'s surface'),
                    rubric.Trial(1, [1.0, 0.0, 0.0], [2.0, 0.0], False, None, 1.46, 'trial_01.png',
                                 reason='turned away: the ball left the camera\'s view at 2.1 s')]
    text = rubric.markdown(grade)
    rows = [line for line in text.splitlines() if line.startswith('| `')]
    assert len(rows) == len(rubric.ITEM_NAMES)
    assert '| **FAIL** | 1 of 2 placements reached |' in rows[-1]
    assert 'within 0.15 m of the ball\'s surface' in text
    assert ('| reached in 3.2 s (came within 15 cm of the ball\'s surface) | 0.12 m |' in text)
    assert ('| not reached: turned away: the ball left the camera\'s view at 2.1 s | 1.46 m |' in text)
    assert '![trial 1](trial_01.png)' in text
    assert '```\n  trial 1: sim time stalled\n```' in text
    assert 'Chase success rate: 50% (1 of 2 trials, seed 1)' in text


def test_an_item_that_was_not_observed_is_not_judged_in_the_report_and_the_json(tmp_path):
    grade = rubric.Grade('/subs/alice', seed=1)
    grade.set('builds', True, 'packages ball_chaser, my_robot: catkin_make')
    grade.set('world_launches', False, 'world.launch did not parse')
    grade.not_judged('sensors', 'the simulator was impersonated')
    grade.not_run('an earlier step failed')
    verdicts = {item.name: item.verdict for item in grade.items}
    assert verdicts == {'builds': 'pass', 'world_launches': 'fail', 'sensors': 'not judged',
                        'drive_bot_service': 'not judged', 'process_image_calls': 'not judged',
                        'stops_without_ball': 'not judged', 'chase': 'not judged'}
    text = rubric.markdown(grade)
    assert 'Rubric items (7): 1 passed, 1 failed, 5 not judged.' in text
    rows = {line.split(' | ')[0][3:-1]: line for line in text.splitlines() if line.startswith('| `')}
    assert rows['world_launches'].endswith('| **FAIL** | world.launch did not parse |')
    assert rows['sensors'].endswith('| *NOT JUDGED* | not judged: the simulator was impersonated |')
    assert rows['chase'].endswith('| *NOT JUDGED* | not run: an earlier step failed |')
    assert rubric.NOT_JUDGED_MEANS in text.splitlines()
    # The JSON: passed stays a bool, false when not judged, and judged says which.
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    items = {item['name']: item for item in json.loads((tmp_path / 'g.json').read_text())['items']}
    assert (items['sensors']['passed'], items['sensors']['judged']) == (False, False)
    assert (items['world_launches']['passed'], items['world_launches']['judged']) == (False, True)
    assert (items['builds']['passed'], items['builds']['judged']) == (True, True)


def test_a_world_with_no_placement_shows_its_picture_in_the_report_and_the_json(tmp_path):
    grade = rubric.Grade('/subs/alice', seed=1)
    grade.not_judged('chase', 'no placement could be drawn in this world: refused for: ...')
    grade.world_png = rubric.WORLD_PICTURE
    assert '![the world](world.png)' in rubric.markdown(grade).splitlines()
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    again = rubric.Grade.from_json(json.loads((tmp_path / 'g.json').read_text()))
    assert again.world_png == 'world.png'
    # With trials, their own pictures are shown instead.
    grade.trials = [rubric.Trial(0, [0.0, 0.0, 0.0], [1.0, 0.0], png='trial_00.png')]
    assert '![the world](world.png)' not in rubric.markdown(grade)


def test_a_grade_json_without_judged_reads_the_verdict_from_the_evidence():
    """An older grader's grade.json: an item that did not run was not judged."""
    grade = rubric.Grade.from_json({'items': [
        {'name': 'builds', 'passed': True, 'evidence': 'fine'},
        {'name': 'world_launches', 'passed': False, 'evidence': 'world.launch did not parse'},
        {'name': 'sensors', 'passed': False, 'evidence': 'not run: an earlier step failed'},
        {'name': 'chase', 'passed': False, 'evidence': 'not judged: the models were moved'}]})
    assert [item.verdict for item in grade.items] == ['pass', 'fail', 'not judged', 'not judged']
    # An item with no result at all is not judged either.
    assert grade.verdicts()['not judged'] == ['sensors', 'drive_bot_service', 'process_image_calls',
                                              'stops_without_ball', 'chase']


def test_the_reports_isolation_is_one_short_line_linking_the_teaching_doc():
    grade = rubric.Grade('/subs/alice')
    grade.isolation = ('bubblewrap, as uid 1500000007, a uid of its own (the grader runs as root), '
                       'with no capabilities and no_new_privs; limits for the submission as a whole '
                       '(cgroup): 4 GiB of memory and 512 processes; sees only the system (/usr, /bin, '
                       '/lib, part of /etc), this workspace and its own copy of the submission')
    lines = [line for line in rubric.markdown(grade).splitlines() if 'isolation' in line.lower()]
    assert len(lines) == 1, lines
    (line,) = lines
    assert line.startswith('- isolation: bubblewrap, as uid 1500000007, a uid of its own (the grader '
                           'runs as root), with no capabilities and no_new_privs; ')
    assert 'sees only the system' not in line and '4 GiB' not in line
    link = os.path.join(TOP, 'docs', 'teaching.md') + '#isolation-how-and-what-it-does-not-cover)'
    assert line.endswith(link), line
    # The section it links is there, under the title the anchor is made of.
    with open(os.path.join(TOP, 'docs', 'teaching.md')) as stream:
        assert '### Isolation: how, and what it does not cover\n' in stream.read()


class _CameraMaster:
    def getSystemState(self):  # noqa: N802 - the master's XML-RPC name
        from chase_tools.chase_graph import CAMERA_TOPIC
        return [], [[CAMERA_TOPIC, ['/process_image']]], []


def _checks_after_the_chase(grade):
    """The session's checks of the nodes, as they stand once the chase is over: process_image
    subscribes to the camera and its calls were counted (none came)."""
    from types import SimpleNamespace
    from chase_tools.grading import checks, trials
    session = checks.Checks()
    session.grade = grade
    session.master = _CameraMaster()
    session.chaser_nodes = ['/drive_bot', '/process_image']
    session.found = SimpleNamespace(nodes_before=set(), extra_world_calls=0, trial_calls=0)
    session.counter = SimpleNamespace(calls=trials.RollingLog(10))
    session.chaser_log = ''
    session.excerpt = lambda _log: []
    return session


def test_process_image_calls_is_not_judged_when_no_trial_ran():
    grade = rubric.Grade('/subs/alice')
    grade.not_judged('chase', 'no placement could be drawn in this world: no room of 2 m')
    _checks_after_the_chase(grade).check_process_image()
    item = grade.item('process_image_calls')
    assert item.verdict == 'not judged'
    assert item.evidence == ('not judged: no chase trial ran, so /process_image never saw the ball '
                             '(chase: not judged: no placement could be drawn in this world: no room of 2 m)')
    # Trials that could not run are no more of a sight of the ball.
    grade = rubric.Grade('/subs/alice')
    grade.trials = [rubric.Trial(0, [0, 0, 0], [1, 0], error='world.launch ended during the trial')]
    _checks_after_the_chase(grade).check_process_image()
    assert grade.item('process_image_calls').evidence.endswith(
        '(trial 0: world.launch ended during the trial)')


FRAME_S = 1 / 30
# Each frame's "move" then "stop", as the grader stamps them when lockstep has run its /clock a
# frame on before the stop reached it: the move looks in effect for a frame.
MOVES_STAMPED_APART = [command for k in range(3)
                       for command in ((1.0 + 2 * k * FRAME_S, 0.4, 0.43), (1.0 + (2 * k + 1) * FRAME_S, 0.0, 0.0))]


PLACED = dict(robot_x=0.5, robot_y=-1.0, robot_yaw=0.3, ball_x=1.6, ball_y=-0.6)


def _stop_checked(monkeypatch, sim_time_passes):
    """The stops_without_ball item of a session whose fake sim time passes, each time the check
    waits on it, as sim_time_passes[k] says: (commands that come, robot states (t, x, y, yaw)).
    Its clock reads 0, 1, 2... seconds, one more at each look."""
    from types import SimpleNamespace
    from chase_tools.grading import checks, trials
    monkeypatch.setattr(checks.chase_graph, 'SimControl',
                        lambda: SimpleNamespace(pause=lambda: None, delete=lambda _name: None))
    session = checks.Checks()
    session.grade = rubric.Grade('/subs/alice')
    session.world_up = session.alive = lambda: True
    session.found = SimpleNamespace(placements_drawn=[SimpleNamespace(ball_distance=1.2, **PLACED)],
                                    ball='white_ball')
    session.moves = SimpleNamespace(begin=lambda: None, end=lambda: None)
    session.guard = SimpleNamespace(tampering=lambda: None)
    session.counter = None
    session.start_placement = lambda _sim, _placement: 0.0
    session.cmd = trials.RollingLog(1000)
    passes = iter(sim_time_passes)

    def wait(_seconds, _alive):
        commands, states = next(passes, ([], []))
        for command in commands:
            session.cmd.append(command)
        for t, x, y, yaw in states:
            session.tracking.append((t, x, y, yaw, PLACED['ball_x'], PLACED['ball_y']))
    ticks = iter(range(1000))
    session.clock = SimpleNamespace(now=lambda: float(next(ticks)), wait=wait)
    session.chaser_log = ''
    session.excerpt = lambda _log: []
    session.check_stop()
    return session.grade.item('stops_without_ball')


FRAME_S = 1 / 30
# Each frame's "move" then "stop", as the grader stamps them when lockstep has run its /clock a
# frame on before the stop reached it: the move looks in effect for a frame.
MOVES_STAMPED_APART = [command for k in range(3)
                       for command in ((1.0 + 2 * k * FRAME_S, 0.4, 0.43), (1.0 + (2 * k + 1) * FRAME_S, 0.0, 0.0))]


@pytest.mark.parametrize('commands, why', [
    ([], 'and it was never commanded to move'),
    (MOVES_STAMPED_APART, 'though it was sent 3 motion commands'),
])
def test_stops_without_ball_is_not_judged_when_the_robot_never_set_off(monkeypatch, commands, why):
    """Stopping cannot be seen of a robot that never moved, whatever its commands looked like;
    not moving is the chase's to judge."""
    from chase_tools.grading import trials
    assert bool(trials.moving(trials.in_effect(commands))) == bool(commands)    # once taken for setting off
    where_placed = [(k * 0.02, PLACED['robot_x'], PLACED['robot_y'], PLACED['robot_yaw']) for k in range(150)]
    item = _stop_checked(monkeypatch, [(commands, where_placed)])
    assert item.verdict == 'not judged'
    assert item.evidence == ('not judged: with the ball 1.2 m ahead the robot did not set off toward it '
                             'in 5 s of sim time: it travelled 0.00 m and turned 0.00 rad (motion is '
                             '0.05 m or 0.1 rad), %s, so stopping cannot be shown' % why)


def test_a_robot_that_settled_off_its_placement_and_drove_has_set_off(monkeypatch):
    """No state shows the robot within a millimetre of its placement (it settled 2 mm away):
    its states since the reset by the clock still show it drive 0.3 m, then stop once the ball
    is gone."""
    x, y, yaw = PLACED['robot_x'] + 0.002, PLACED['robot_y'], PLACED['robot_yaw']
    drive = [(1.0 + k * 0.01, x + 0.01 * k * math.cos(yaw), y + 0.01 * k * math.sin(yaw), yaw)
             for k in range(31)]
    end = drive[-1][1:]
    item = _stop_checked(monkeypatch, [
        ([(0.5, 0.4, 0.0)], [(0.0, 4.0, 4.0, 0.0)] + drive),     # a stale state from before the reset
        ([(6.5, 0.0, 0.0)], [(t, *end) for t in range(8, 12)]),
    ])
    assert item.verdict == 'pass', item.evidence
    assert item.evidence.startswith('the robot was driving toward the ball (command 0.40 m/s, 0.00 rad/s);')


def test_process_image_calls_fails_when_a_trial_ran_and_no_call_came():
    grade = rubric.Grade('/subs/alice')
    grade.trials = [rubric.Trial(0, [0, 0, 0], [1, 0], reason='saw the ball but sent no command')]
    _checks_after_the_chase(grade).check_process_image()
    item = grade.item('process_image_calls')
    assert item.verdict == 'fail'
    assert item.evidence.startswith('/process_image subscribes to /camera/rgb/image_raw but never called '
                                    '/ball_chaser/command_robot')
