"""The rubric run's session without a master: the parameters it reads and refuses, the
stability advisory (a line of the report, never an item), and how a session's end is named."""
import json
import os

import pytest

from chase_tools.grading import rubric
from session_fakes import DescriptionMaster, ParamMaster, a_session

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.realpath(os.path.join(HERE, '..', '..', '..', '..'))     # this workspace's checkout


def test_parameters_of_the_wrong_type_are_named_and_not_used(tmp_path, monkeypatch):
    """roslaunch types a <param> by how its value reads: value="3" is an int, "true" a bool,
    and a <rosparam> gives a dictionary. The grader reads three of them."""
    session = a_session(tmp_path, monkeypatch)
    session.master = ParamMaster({'/flatsim/world_name': 3, '/robot_description': {'robot': 'x'},
                                  '/flatsim/model_states_rate': 'fast'})
    notes = []
    assert session.typed_param('/flatsim/world_name', str, 'a file name', '', notes) == ''
    assert notes == ['the parameter /flatsim/world_name holds 3 (int), not a file name; it was not used']
    assert session.urdf_robot_name() is None
    assert ("the parameter /robot_description holds {'robot': 'x'} (dict), not URDF; it was not used"
            in session.grade.notes)

    class Sim:
        def time_step(self):
            return 0.001
    session.read_state_schedule(Sim())
    assert session.found.states_period == pytest.approx(1 / 50.0)
    assert any('/flatsim/model_states_rate holds \'fast\' (str)' in note for note in session.grade.notes)
    session.master = ParamMaster({'/flatsim/model_states_rate': True})
    session.read_state_schedule(Sim())
    assert session.found.states_period == pytest.approx(1 / 50.0)
    session.master = ParamMaster({'/flatsim/model_states_rate': 20})
    session.read_state_schedule(Sim())
    assert session.found.states_period == pytest.approx(1 / 20.0)


# -- the stability advisory ------------------------------------------------------------------------

FRONT_WHEELER = os.path.join(TOP, 'catkin_ws', 'src', 'flatsim', 'test', 'fixtures', 'robots',
                             'front_wheels_no_casters.urdf')
TIPPING = ('robot stability: may tip over: centre of mass (0.033, 0.000) m of 12.00 kg is 0.167 m outside '
           'the support line (no polygon) (0.200, -0.175) (0.200, 0.175) of left_wheel, right_wheel '
           '(margin -0.167 m; a stable design keeps it at least 0.02 m inside)')


def test_a_robot_that_would_tip_gets_an_advisory_and_no_failed_item(tmp_path, monkeypatch):
    session = a_session(tmp_path, monkeypatch)
    with open(FRONT_WHEELER, encoding='utf-8') as stream:
        session.master = DescriptionMaster({'/robot_description': stream.read()})
    session.read_robot_geometry()
    assert session.grade.advisories == [TIPPING]
    assert session.found.geometry is not None
    assert session.grade.items == [] and session.grade.notes == []


def test_the_advisory_is_a_line_of_the_report_and_of_the_json_not_an_item(tmp_path):
    from chase_tools.grading import formats
    grade = rubric.Grade('/subs/alice', seed=1)
    for name in rubric.ITEM_NAMES:
        grade.set(name, True, 'evidence of %s' % name)
    grade.advisories.append(TIPPING)
    assert grade.passed
    text = rubric.markdown(grade)
    assert 'Rubric items (7): 7 passed, 0 failed, 0 not judged.' in text
    assert 'Advisory, not a rubric item: %s' % TIPPING in text.splitlines()
    assert '**FAIL**' not in text
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    again = rubric.Grade.from_json(json.loads((tmp_path / 'g.json').read_text()))
    assert again.advisories == [TIPPING] and again.passed
    scope = formats.gradescope(grade)
    assert scope['output'].endswith('\nAdvisory, not a rubric item: %s' % TIPPING)
    assert scope['score'] == sum(test['max_score'] for test in scope['tests'])


def test_a_session_a_signal_ended_says_which():
    from chase_tools.grading.submission_grade import exit_text
    assert exit_text(-9) == 'killed by SIGKILL'
    assert exit_text(1) == 'exit 1'
