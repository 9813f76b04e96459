"""The grade in other tools' formats. Pure: no ROS.

gradescope: the results.json that Gradescope's autograder harness reads from
/autograder/results/results.json after running run_autograder. One test per
rubric item, worth one point, in the rubric's order; its output is the item's
evidence (the trials too, for the chase). The format's fields:

    {"score": 5.0,                       # the sum of the tests' scores
     "execution_time": 61,               # seconds
     "output": "...", "output_format": "text",
     "stdout_visibility": "hidden",      # the grader's own output is for the staff
     "tests": [{"name": "builds", "number": "1", "score": 1.0, "max_score": 1.0,
                "status": "passed" | "failed", "output": "...", "output_format": "text",
                "visibility": "visible"}, ...]}

Gradescope knows only passed and failed. A test whose item was not judged
(nothing of it could be observed) scores 0 with status "failed", the tag
"not judged", extra_data {"verdict": "not judged"}, and an output whose first
line says so (NOT_JUDGED_NOTE), so that a teacher can tell it from a failure
and judge it.

The course's other rubric rows (rubric.COURSE_ROWS) follow the items, one test each, when the
grade judged them: a counted row is worth one point; a counted "stand out" row is extra credit
(max_score 0, one point when it passed); a row not counted (--rubric) scores nothing, with the
tag "not counted".
"""
import json

from chase_tools.grading import rubric

FORMATS = ('grade', 'gradescope')
NOT_COUNTED_NOTE = 'NOT COUNTED: this rubric row was left out of the grade (--rubric); shown for the record.'
GRADESCOPE_ITEM_POINTS = 1.0
NOT_JUDGED_NOTE = ('NOT JUDGED: the grader could not observe this item (the evidence below says '
                   'why), so it is neither passed nor failed; it scores 0 until a teacher judges it.')


def trial_lines(grade):
    lines = []
    for trial in grade.trials:
        outcome = rubric.trial_outcome(trial, reached='reached the ball in',
                                       missed='did not reach the ball:')
        if not trial.error and not trial.reached:
            outcome += ' (closest %s of its surface)' % (
                '%.2f m' % trial.closest if trial.closest is not None else 'unknown')
        lines.append('trial %d: robot at (%.2f, %.2f, %.2f), ball at (%.2f, %.2f): %s'
                     % (trial.index, *trial.robot, *trial.ball, outcome))
    return lines


def gradescope(grade, execution_time=None):
    """Gradescope's results.json for one graded submission, as a dict."""
    tests = []
    for number, name in enumerate(rubric.ITEM_NAMES, 1):
        item = grade.item(name) or rubric.Item(name, False, 'not run')
        output = [rubric.DESCRIPTIONS[name] + '.', '', item.evidence]
        if not item.judged:
            output = [NOT_JUDGED_NOTE, ''] + output
        if name == 'chase' and grade.trials:
            output += [''] + trial_lines(grade)
        test = {'name': name, 'number': str(number),
                'score': GRADESCOPE_ITEM_POINTS if item.passed else 0.0,
                'max_score': GRADESCOPE_ITEM_POINTS,
                'status': 'passed' if item.passed else 'failed',
                'output': '\n'.join(output), 'output_format': 'text',
                'visibility': 'visible'}
        if not item.judged:
            test.update(tags=[rubric.UNJUDGED], extra_data={'verdict': rubric.UNJUDGED})
        tests.append(test)
    tests += row_tests(grade, len(tests))
    verdicts = grade.verdicts()
    results = {'score': sum(test['score'] for test in tests),
               'output': 'Go Chase It rubric: %d of %d items passed, %d failed, %d not judged. '
                         'Chase: %d of %d trials reached the ball (seed %d).'
                         % (len(verdicts[rubric.PASS]), len(rubric.ITEM_NAMES), len(verdicts[rubric.FAIL]),
                            len(verdicts[rubric.UNJUDGED]), sum(t.reached for t in grade.trials),
                            len(grade.trials), grade.seed)
                         + (' ' + rubric.rows_text(grade) if rubric.rows_text(grade) else '')
                         + ''.join('\nAdvisory, not a rubric item: %s' % advice for advice in grade.advisories),
               'output_format': 'text', 'stdout_visibility': 'hidden', 'tests': tests}
    if execution_time is not None:
        results['execution_time'] = int(round(execution_time))
    return results


def row_tests(grade, before):
    """The tests of the course's other rubric rows, numbered after the items'."""
    if not grade.course_rows:
        return []
    tests = []
    for number, row in enumerate(grade.rows_in_order(), before + 1):
        counted, stand_out = row.name in grade.counted_rows, row.name in rubric.STAND_OUT
        worth = GRADESCOPE_ITEM_POINTS if counted else 0.0
        output = [rubric.ROW_DESCRIPTIONS[row.name] + '.', '', row.evidence]
        if not row.judged:
            output = [NOT_JUDGED_NOTE, ''] + output
        if not counted:
            output = [NOT_COUNTED_NOTE, ''] + output
        test = {'name': row.name, 'number': str(number),
                'score': worth if row.passed else 0.0,
                'max_score': 0.0 if stand_out else worth,
                'status': 'passed' if row.passed else 'failed',
                'output': '\n'.join(output), 'output_format': 'text', 'visibility': 'visible'}
        tags = ([] if row.judged else [rubric.UNJUDGED]) + ([] if counted else ['not counted'])
        if tags:
            test['tags'] = tags
        if not row.judged:
            test['extra_data'] = {'verdict': rubric.UNJUDGED}
        tests.append(test)
    return tests


def write(grade, path, fmt, execution_time=None):
    """grade as fmt ('grade': the grader's own JSON; 'gradescope') at path."""
    data = grade.as_json() if fmt == 'grade' else gradescope(grade, execution_time)
    rubric.write_whole(path, json.dumps(data, indent=2) + '\n')
