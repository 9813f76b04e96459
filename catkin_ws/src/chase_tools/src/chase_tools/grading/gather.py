"""A class's results, gathered from each submission's grade.json. Pure: no ROS.

A class grade (local, or one Slurm array task per submission) leaves
DIR/<name>/grade.json for every submission it graded. From those files alone
this writes

  DIR/summary.md   a table, one line per submission, linking its report;
  DIR/grades.csv   one row per submission, one column per rubric item
                   (pass, fail or not judged), one per course rubric row (the same,
                   "(not counted)" after a row --rubric left out), chase_reached, chase_trials, success_rate,
                   the wall time (total_s, build_s, rubric_run_s), report,
                   and notes: the evidence of each failure on one line.

A grade.json that is missing or cannot be read is a row that says so, with
empty item cells: the submission was not graded, which is not a failure of
the student's.
"""
import csv
import io
import json
import os
import sys
from dataclasses import dataclass
from typing import Optional

from chase_tools.grading import rubric

GRADE_FILE = 'grade.json'
# What the grader writes beside grade.json while it runs (the class grade's log of it).
LOG_FILE = 'grade.log'
SUMMARY_FILE = 'summary.md'
CSV_FILE = 'grades.csv'
# similarity.MARKDOWN_FILE, written beside the summary before the class is graded.
SIMILARITY_FILE = 'similarity.md'
WALL_TIME_COLUMNS = (('total_s', 'total'), ('build_s', 'build'), ('rubric_run_s', 'rubric_run'))
CSV_COLUMNS = (('submission',) + rubric.ITEM_NAMES + rubric.ROW_NAMES
               + ('chase_reached', 'chase_trials', 'success_rate')
               + tuple(column for column, _key in WALL_TIME_COLUMNS) + ('report', 'notes'))
# A spreadsheet takes a cell that starts with one of these for a formula.
FORMULA_STARTS = ('=', '+', '-', '@', '\t', '\r')
NOT_RUN = 'not run: '


@dataclass
class Row:
    """One submission of a class: its grade, or why there is none."""
    name: str
    grade: Optional[rubric.Grade]
    problem: str = ''
    logged: bool = False                # the grader's log of it is there

    @property
    def not_graded(self):
        return 'not graded: ' + self.problem


def read(report_dir, name, missing_reason=''):
    """The Row of report_dir/name. missing_reason says why a grade.json may be missing
    (the Slurm task's end, say); the grader's log is named otherwise."""
    path = os.path.join(report_dir, name, GRADE_FILE)
    logged = os.path.exists(os.path.join(report_dir, name, LOG_FILE))
    try:
        with open(path) as stream:
            data = json.load(stream)
    except FileNotFoundError:
        if not missing_reason:
            missing_reason = ('the grader did not finish; see %s/%s' % (name, LOG_FILE) if logged
                              else 'the grader did not run on it')
        return Row(name, None, 'no %s: %s' % (GRADE_FILE, missing_reason), logged)
    except (OSError, ValueError) as error:
        return Row(name, None, '%s/%s cannot be read: %s' % (name, GRADE_FILE, error), logged)
    try:
        grade = rubric.Grade.from_json(data)
    except (AttributeError, TypeError, KeyError) as error:
        return Row(name, None, '%s/%s is not a grade: %s' % (name, GRADE_FILE, error), logged)
    return Row(name, grade, logged=logged)


def names_in(report_dir):
    """The submissions a report folder holds: every subfolder the grader wrote into."""
    return sorted(entry for entry in os.listdir(report_dir)
                  if any(os.path.exists(os.path.join(report_dir, entry, written))
                         for written in (GRADE_FILE, LOG_FILE)))


def read_all(report_dir, names, missing_reasons=None):
    missing_reasons = missing_reasons or {}
    return [read(report_dir, name, missing_reasons.get(name, '')) for name in names]


def write(report_dir, rows, how=''):
    """summary.md and grades.csv in report_dir. how: a line on how the class was graded."""
    similar = os.path.exists(os.path.join(report_dir, SIMILARITY_FILE))
    rubric.write_whole(os.path.join(report_dir, SUMMARY_FILE), summary_markdown(rows, how, similar))
    write_csv(rows, os.path.join(report_dir, CSV_FILE))


def passed(rows):
    """True when every submission was graded and passed every item."""
    return all(row.grade is not None and row.grade.passed for row in rows)


def reached(grade):
    return sum(trial.reached for trial in grade.trials)


def summary_line(grade):
    """One line for a terminal: items passed (and how many failed and were not judged), the
    chase, the items failed, the items not judged."""
    verdicts = grade.verdicts()
    failed, unjudged = verdicts[rubric.FAIL], verdicts[rubric.UNJUDGED]
    counts = ' (%d failed, %d not judged)' % (len(failed), len(unjudged)) if failed or unjudged else ''
    return '%d/%d items%s, chase %d/%d%s%s' % (
        len(verdicts[rubric.PASS]), len(rubric.ITEM_NAMES), counts, reached(grade),
        len(grade.trials), ('; failed: %s' % ', '.join(failed)) if failed else '',
        ('; not judged: %s' % ', '.join(unjudged)) if unjudged else '')


def row_line(row):
    return summary_line(row.grade) if row.grade is not None else row.not_graded


def _verdict(grade, name):
    """'pass', 'fail' or 'not judged' (an item with no result was not judged)."""
    item = grade.item(name)
    return item.verdict if item is not None else rubric.UNJUDGED


def _md_cell(text):
    return rubric.md_text(text)


def _md_link(name, path):
    """[name](name/path): a folder's name is the teacher's (or a submission's) choice."""
    from urllib.parse import quote
    return '[%s](%s/%s)' % (rubric.md_text(name), quote(name), path)


def summary_markdown(rows, how='', similar=False):
    graded = [row for row in rows if row.grade is not None]
    lines = ['# Go Chase It: %d submissions' % len(rows), '']
    if how:
        lines += [how, '']
    unjudged = sum(bool(row.grade.verdicts()[rubric.UNJUDGED]) for row in graded)
    lines += ['%d graded, %d of them passed every item%s%s.' % (
                 len(graded), sum(row.grade.passed for row in graded),
                 '; %d with items not judged (nothing of them could be observed: for a teacher '
                 'to judge, counted apart from the failures)' % unjudged if unjudged else '',
                 '; %d not graded' % (len(rows) - len(graded)) if len(rows) > len(graded) else ''),
             'Every item of every submission, with the evidence of each failure: '
             '[%s](%s).' % (CSV_FILE, CSV_FILE)]
    if similar:
        lines.append('Pairs of submissions whose code is unusually alike (evidence, not a grade): '
                     '[%s](%s).' % (SIMILARITY_FILE, SIMILARITY_FILE))
    lines += ['',
             '| submission | items | %s | chase | wall time |' % ' | '.join('`%s`' % n for n in rubric.ITEM_NAMES[:-1]),
             '|---|---|%s---|---|' % ('---|' * (len(rubric.ITEM_NAMES) - 1))]
    for row in rows:
        if row.grade is None:
            cells = [_md_cell(row.not_graded)] + [''] * (len(rubric.ITEM_NAMES) + 1)
            name = _md_link(row.name, LOG_FILE) if row.logged else _md_cell(row.name)
            lines.append('| %s | %s |' % (name, ' | '.join(cells)))
            continue
        cells = [rubric.VERDICT_CELLS[_verdict(row.grade, n)] for n in rubric.ITEM_NAMES[:-1]]
        chase = '%s %d/%d' % (rubric.VERDICT_CELLS[_verdict(row.grade, 'chase')],
                              reached(row.grade), len(row.grade.trials))
        lines.append('| %s | %s | %s | %s | %s |' % (
            _md_link(row.name, 'report.md'), rubric.verdicts_text(row.grade), ' | '.join(cells),
            chase, rubric.wall_time_text(row.grade)))
    return '\n'.join(lines) + '\n'


def notes(grade):
    """The first line of each failed item's evidence; items that did not run, grouped by why."""
    said, not_run = [], {}
    for name in rubric.ITEM_NAMES:
        item = grade.item(name)
        if item is None:
            not_run.setdefault('no result', []).append(name)
        elif not item.passed:
            first = item.evidence.split('\n', 1)[0]
            if first.startswith(NOT_RUN):
                not_run.setdefault(first[len(NOT_RUN):], []).append(name)
            else:
                said.append('%s: %s' % (name, first))
    said += ['not run (%s): %s' % (why, ', '.join(names)) for why, names in not_run.items()]
    return ' | '.join(said)


def csv_safe(text):
    """One line a spreadsheet shows as text: no line breaks or control characters, and no
    leading character that would make it a formula."""
    text = ''.join(' ' if ord(char) < 32 or char == '\x7f' else char for char in str(text))
    return "'" + text if text.startswith(FORMULA_STARTS) else text


def csv_row(row):
    if row.grade is None:
        values = {'submission': row.name, 'notes': row.not_graded}
    else:
        grade = row.grade
        values = {name: _verdict(grade, name) for name in rubric.ITEM_NAMES}
        if grade.course_rows:
            values.update({row.name: row.verdict + ('' if row.name in grade.counted_rows else ' (not counted)')
                           for row in grade.rows_in_order()})
        values.update(submission=row.name, chase_reached=reached(grade), chase_trials=len(grade.trials),
                      success_rate='%.3g' % grade.success_rate,
                      report='%s/report.md' % row.name, notes=notes(grade))
        values.update({column: grade.wall_time[key] for column, key in WALL_TIME_COLUMNS
                       if key in grade.wall_time})
    return [csv_safe(values.get(column, '')) for column in CSV_COLUMNS]


def write_csv(rows, path):
    text = io.StringIO()
    writer = csv.writer(text)
    writer.writerow(CSV_COLUMNS)
    for row in rows:
        writer.writerow(csv_row(row))
    rubric.write_whole(path, text.getvalue())


def folder_json(rows, submission_paths=None):
    """`--json` for a class: {"submissions": [grade JSON with its name, ...]}. A submission
    that was not graded has every item failed with the reason."""
    submission_paths = submission_paths or {}
    entries = []
    for row in rows:
        grade = row.grade
        if grade is None:
            grade = rubric.Grade(submission_paths.get(row.name, row.name))
            grade.not_run(row.problem)
        entries.append(dict(grade.as_json(), name=row.name))
    return {'submissions': entries}


def status(rows, json_path='', submission_paths=None):
    """A class grade's exit status, once --json FILE is written: 0 when every submission was
    graded and passed every item, 1 otherwise, 2 when there are no rows (nothing could run)."""
    if rows is None:
        return 2
    if json_path:
        rubric.write_whole(json_path, json.dumps(folder_json(rows, submission_paths), indent=2) + '\n')
    return 0 if passed(rows) else 1


def gather_folder(report_dir, json_path=''):
    """grade --gather DIR: the class's summary and CSV from the grades already in DIR; the exit
    status."""
    names = names_in(report_dir)
    if not names:
        print('grade: %s holds no graded submissions (no %s/<name>/%s)'
              % (report_dir, report_dir, GRADE_FILE), file=sys.stderr)
        return 2
    rows = read_all(report_dir, names)
    write(report_dir, rows)
    for row in rows:
        print('%-30s %s' % (row.name, row_line(row)))
    print('grade: wrote %s and %s' % (os.path.join(report_dir, SUMMARY_FILE),
                                      os.path.join(report_dir, CSV_FILE)))
    return status(rows, json_path)
