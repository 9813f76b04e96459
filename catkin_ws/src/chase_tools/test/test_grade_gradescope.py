"""Gradescope's autograder: docker/gradescope/run_autograder on a folder laid out as Gradescope
lays out /autograder, and the results.json it leaves, checked against a schema of Gradescope's
documented format (fixtures/gradescope_results.schema.json)."""
import json
import os
import shutil
import subprocess
import sys

import jsonschema
import pytest

from chase_tools.grading import rubric, sandbox

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.abspath(os.path.join(HERE, '..', '..', '..', '..'))
WRAPPER = os.path.join(TOP, 'docker', 'gradescope', 'run_autograder')
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402

with open(os.path.join(HERE, 'fixtures', 'gradescope_results.schema.json')) as _stream:
    SCHEMA = json.load(_stream)
GRADE_TIMEOUT_S = 600

pytestmark = pytest.mark.skipif(sandbox.check() is not None,
                                reason='the grader needs bubblewrap: %s' % sandbox.check())


def autograder(tmp_path, variant):
    """tmp_path/autograder as Gradescope builds it: source (this checkout), run_autograder
    beside it, and the student's files in submission."""
    root = tmp_path / 'autograder'
    root.mkdir()
    os.symlink(TOP, root / 'source')
    shutil.copy(WRAPPER, root / 'run_autograder')
    shutil.copytree(variants.compose(variant, tmp_path / 'uploaded'), root / 'submission')
    return root


def run_autograder(root):
    # Gradescope's harness starts it from /autograder with nothing of this environment.
    env = {name: os.environ[name] for name in ('PATH', 'HOME', 'LANG') if name in os.environ}
    env['PATH'] = '/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin'
    proc = subprocess.run([str(root / 'run_autograder'), '--trials', '1', '--timeout', '30'],
                          cwd=root, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, timeout=GRADE_TIMEOUT_S, check=False)
    with open(root / 'results' / 'results.json') as stream:
        return proc, json.load(stream)


def test_the_schema_is_a_valid_json_schema_that_rejects_what_gradescope_would():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    validator = jsonschema.Draft202012Validator(SCHEMA)
    assert validator.is_valid({'tests': [{'score': 1.0, 'max_score': 1.0, 'status': 'passed'}]})
    assert not validator.is_valid({'tests': [{'max_score': 1.0}]})               # no score anywhere
    assert not validator.is_valid({'score': 1, 'tests': [{'score': 1, 'status': 'ok'}]})
    assert not validator.is_valid({'score': 1, 'visibility': 'students'})


def test_a_correct_submission_scores_every_item(tmp_path):
    proc, results = run_autograder(autograder(tmp_path, 'py_correct'))
    assert proc.returncode == 0, proc.stdout
    jsonschema.validate(results, SCHEMA)
    assert [test['name'] for test in results['tests']] == list(rubric.ITEM_NAMES + rubric.ROW_NAMES)
    items = results['tests'][:len(rubric.ITEM_NAMES)]
    assert all(test['status'] == 'passed' and test['score'] == test['max_score'] == 1.0
               for test in items), results
    # The course's other rows follow: its Python nodes are not the C++ the course asks for.
    rows = {test['name']: test for test in results['tests'][len(rubric.ITEM_NAMES):]}
    assert (rows['cpp_nodes']['status'], rows['cpp_nodes']['score']) == ('failed', 0.0)
    assert 'are Python' in rows['cpp_nodes']['output']
    assert results['score'] == len(rubric.ITEM_NAMES) + sum(test['score'] for test in rows.values())
    assert results['output'].startswith('Go Chase It rubric: 7 of 7 items passed, 0 failed, 0 not judged. '
                                        'Chase: 1 of 1')
    assert 'Course rubric rows counted (5): ' in results['output']
    chase = items[-1]['output']
    assert chase.startswith(rubric.DESCRIPTIONS['chase'])
    assert 'trial 0: robot at (' in chase and 'reached the ball in ' in chase
    assert results['execution_time'] > 0


def test_a_submission_that_does_not_build_scores_nothing_and_says_why(tmp_path):
    proc, results = run_autograder(autograder(tmp_path, 'py_cmake_typo'))
    # A failed submission is a grade, not an autograder failure.
    assert proc.returncode == 0, proc.stdout
    jsonschema.validate(results, SCHEMA)
    items = results['tests'][:len(rubric.ITEM_NAMES)]
    assert sum(test['score'] for test in items) == 0
    builds = results['tests'][0]
    assert builds['status'] == 'failed' and builds['score'] == 0.0 and builds['max_score'] == 1.0
    assert 'CMake configuration failed' in builds['output']
    assert 'Unknown CMake command "generate_message"' in builds['output']
    assert items[-1]['output'].endswith('not run: the build failed')
    # The rows the files decide are judged; the spawned robot is not, for none was spawned.
    rows = {test['name']: test for test in results['tests'][len(rubric.ITEM_NAMES):]}
    assert rows['course_layout']['status'] == 'passed'
    assert rows['robot_differs_from_sample']['tags'] == [rubric.UNJUDGED]
