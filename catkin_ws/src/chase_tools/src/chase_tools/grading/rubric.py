"""The project rubric as the grader checks it, its results, and the report. Pure: no ROS.

The JSON that `grade --json FILE` writes is a contract for scripts and CI:

    {"success_rate": 0.67,                      # reached trials / trials, 0.0 when none ran
     "trials": [{"index": 0, "reached": false, "time_to_ball": null, "closest": 0.11,
                 "robot": [x, y, yaw], "ball": [x, y], "png": "trial_00.png", "error": "",
                 "reason": "stopped short at 11 cm of the ball's surface ...",
                 "record": {"moved_m": 2.3, "gap_at_end": 0.11, ...}}, ...],
     "items": [{"name": "builds", "passed": true, "evidence": "...", "judged": true}, ...],
     "submission": "path", "seed": 0, "reach": 0.15, "isolation": "...",
     "advisories": ["robot stability: stable: ..."],   # advice on the design; no item depends on it
     "folder": "Project 2",                     # the folder graded, relative to submission
     "ignored": ["Project 1/my_robot"],         # its package folders that were not graded
     "worlds": 1,                               # worlds the trials were shared among
     "world_png": "",                           # world.png when no placement could be drawn
     "wall_time": {"total": 14.2, "build": 3.1, "rubric_run": 10.5},   # seconds
     "course_rows": [{"name": "cpp_nodes", "passed": true, "judged": true, "counted": true,
                      "evidence": "..."}, ...]}    # the course's other rubric rows

reach and each trial's closest are gaps from the robot's outline to the ball's
surface (m). reason says how a trial reached the ball or why it did not;
record holds the figures behind it (grading/trials.py).

items holds every name in ITEMS, in that order. evidence is text: its first
line says what was seen; further lines are the log lines behind a failure.
An item's verdict is pass, fail or not judged: judged is false when nothing
of it could be observed (its step did not run, or what it saw cannot be
trusted), and its evidence then starts "not judged: why" ("not run: why"
for a step that never ran, "not finished: why" for one that was stopped);
passed is false for it. A grade.json without judged (an older grader's)
reads the verdict from those words.

course_rows holds every name in COURSE_ROWS, in that order: the rubric's rows
that are not behaviour, judged from the submission's files and what the run
saw (grading/course_rubric.py), with the same verdicts and evidence as items.
counted says whether the row counts toward the grade line (`--rubric`); the
behavioural items and the exit status do not depend on them.
"""
import json
import os
import re
from dataclasses import asdict, dataclass, field
from typing import List, Optional

ITEMS = (
    ('builds', 'the packages build in a fresh overlay workspace'),
    ('world_launches', 'world.launch starts the world with a white ball and spawns the robot'),
    ('sensors', 'the robot has a camera on /camera/rgb/image_raw and a lidar on /scan'),
    ('drive_bot_service', 'drive_bot serves /ball_chaser/command_robot (the course\'s DriveToTarget '
                          'request) and publishes the request on /cmd_vel'),
    ('process_image_calls', 'process_image subscribes to the camera and calls the service'),
    ('stops_without_ball', 'the robot stops when no ball is in view'),
    ('chase', 'seeded placements are chased to the ball'),
)
ITEM_NAMES = tuple(name for name, _ in ITEMS)
# The course's other rubric rows: (name, what the rubric asks, a "stand out" suggestion rather
# than a requirement). Judged by grading/course_rubric.py.
COURSE_ROWS = (
    ('course_layout', 'my_robot and ball_chaser follow the directory structure of the project '
                      'description', False),
    ('robot_differs_from_sample', 'the robot differs from the lesson\'s sample in colour, wheel '
                                  'radius and chassis dimensions', False),
    ('robot_housed_in_world', 'the robot is housed inside the world: spawned within its walls',
     False),
    ('building_editor_world', 'the world was designed with the Building Editor', False),
    ('cpp_nodes', 'drive_bot and process_image are C++ nodes', False),
    ('skid_steer', 'stand out: a skid-steer robot design', True),
    ('ball_any_colour', 'stand out: the robot chases a ball of a colour other than white', True),
)
ROW_NAMES = tuple(name for name, _, _ in COURSE_ROWS)
ROW_DESCRIPTIONS = {name: description for name, description, _ in COURSE_ROWS}
STAND_OUT = frozenset(name for name, _, stand_out in COURSE_ROWS if stand_out)
# The picture of a world in which no trial could be placed.
WORLD_PICTURE = 'world.png'
DESCRIPTIONS = dict(ITEMS)


# The first words of the evidence of an item that was not judged: nothing of it was observed.
NOT_JUDGED = 'not judged: '
NOT_JUDGED_STARTS = (NOT_JUDGED, 'not run', 'not finished: ')
PASS, FAIL, UNJUDGED = 'pass', 'fail', 'not judged'
# A course row that nothing judged.
ROW_NOT_RUN = NOT_JUDGED + 'not run'
VERDICTS = (PASS, FAIL, UNJUDGED)


def says_not_judged(evidence):
    """True when evidence is that of an item nothing of which was observed."""
    return str(evidence).startswith(NOT_JUDGED_STARTS)


@dataclass
class Item:
    name: str
    passed: bool
    evidence: str
    # False: nothing of the item was observed, and its evidence says why. None: read from the
    # evidence's first words (an Item made without it, or an older grade.json).
    judged: Optional[bool] = None

    def __post_init__(self):
        if self.judged is None:
            self.judged = not says_not_judged(self.evidence)
        self.judged = bool(self.judged)
        # An item not judged has not passed either.
        self.passed = bool(self.passed) and self.judged

    @property
    def verdict(self):
        return UNJUDGED if not self.judged else PASS if self.passed else FAIL


@dataclass
class Trial:
    index: int
    robot: List[float]                 # x, y, yaw where it started
    ball: List[float]                  # x, y where the ball started
    reached: bool = False
    time_to_ball: Optional[float] = None
    closest: Optional[float] = None    # m from the robot's outline to the ball's surface
    png: str = ''
    error: str = ''                    # why the trial could not run
    reason: str = ''                   # how it reached the ball, or why it did not
    record: dict = field(default_factory=dict)  # the figures behind the reason
    world: int = 1                     # the world that ran it (1: the session's own)


@dataclass
class Grade:
    submission: str
    items: List[Item] = field(default_factory=list)
    trials: List[Trial] = field(default_factory=list)
    seed: int = 0
    reach: Optional[float] = None
    isolation: str = ''
    notes: List[str] = field(default_factory=list)
    advisories: List[str] = field(default_factory=list)   # judgements that pass or fail nothing
    folder: str = '.'                  # the folder of the submission that was graded
    ignored: List[str] = field(default_factory=list)   # package folders of it left out
    worlds: int = 1                    # worlds the chase trials were shared among
    world_png: str = ''                # the world from above, when no placement could be drawn
    wall_time: dict = field(default_factory=dict)     # seconds: total, build, rubric_run
    course_rows: List[Item] = field(default_factory=list)   # the course's other rubric rows
    counted_rows: List[str] = field(default_factory=lambda: list(ROW_NAMES))   # --rubric

    @property
    def success_rate(self):
        return sum(t.reached for t in self.trials) / len(self.trials) if self.trials else 0.0

    def item(self, name):
        return next((item for item in self.items if item.name == name), None)

    def set(self, name, passed, evidence, log_lines=()):
        """Record an item (replacing an earlier result of the same name): evidence is its first
        line, each log line one more. A line break in either (a name the submission chose can
        hold one) shows as an escape, so the first line stays what was seen."""
        self.put(Item(name, bool(passed), '\n'.join(
            [one_line(evidence)] + [one_line(line) for line in log_lines if line.strip()])))

    def not_judged(self, name, why, log_lines=()):
        """Record an item nothing of which could be observed, saying why."""
        self.set(name, False, NOT_JUDGED + why, log_lines)

    def put(self, item):
        """Record an item whose evidence is already lines (set's), as another grade has it."""
        self.items = [kept for kept in self.items if kept.name != item.name] + [item]

    def not_run(self, reason):
        """Every item not yet recorded is not judged: it did not run, for reason. The failure
        that stopped it counts once, at the item where it was seen."""
        for name in ITEM_NAMES:
            if self.item(name) is None:
                self.set(name, False, 'not run: %s' % reason)

    def row(self, name):
        return next((row for row in self.course_rows if row.name == name), None)

    def set_row(self, name, passed, evidence, judged=None):
        """Record a course row (replacing an earlier result of the same name)."""
        row = Item(name, bool(passed), one_line(evidence), judged)
        self.course_rows = [kept for kept in self.course_rows if kept.name != name] + [row]

    def rows_in_order(self):
        return [self.row(name) or Item(name, False, ROW_NOT_RUN) for name in ROW_NAMES]

    def row_verdicts(self, stand_out=False):
        """{verdict: [row names]} of the counted course rows: the required ones, or with
        stand_out the rubric's suggestions."""
        found = {verdict: [] for verdict in VERDICTS}
        for row in self.rows_in_order():
            if row.name in self.counted_rows and (row.name in STAND_OUT) == stand_out:
                found[row.verdict].append(row.name)
        return found

    @property
    def passed(self):
        return all(self.item(name) is not None and self.item(name).passed for name in ITEM_NAMES)

    def verdicts(self):
        """{verdict: [item names]} for every rubric item, in its order (an item with no result
        was not judged)."""
        found = {verdict: [] for verdict in VERDICTS}
        for name in ITEM_NAMES:
            item = self.item(name)
            found[item.verdict if item is not None else UNJUDGED].append(name)
        return found

    def as_json(self):
        items = [self.item(name) or Item(name, False, 'not run') for name in ITEM_NAMES]
        return {'success_rate': self.success_rate,
                'trials': [asdict(trial) for trial in self.trials],
                'items': [asdict(item) for item in items],
                'submission': self.submission, 'seed': self.seed, 'reach': self.reach,
                'isolation': self.isolation, 'notes': list(self.notes),
                'advisories': list(self.advisories), 'folder': self.folder, 'ignored': list(self.ignored),
                'worlds': self.worlds,
                'world_png': self.world_png, 'wall_time': dict(self.wall_time),
                'course_rows': [dict(asdict(row), counted=row.name in self.counted_rows)
                                for row in self.rows_in_order()]}

    @classmethod
    def from_json(cls, data):
        grade = cls(data.get('submission', ''), seed=data.get('seed', 0), reach=data.get('reach'),
                    isolation=data.get('isolation', ''), notes=list(data.get('notes', [])),
                    advisories=list(data.get('advisories', [])),
                    folder=data.get('folder', '.'), ignored=list(data.get('ignored', [])),
                    worlds=data.get('worlds', 1), world_png=data.get('world_png', ''),
                    wall_time=dict(data.get('wall_time') or {}))
        grade.items = [Item(**item) for item in data.get('items', [])]
        grade.trials = [Trial(**trial) for trial in data.get('trials', [])]
        rows = data.get('course_rows', [])
        grade.course_rows = [Item(row['name'], row.get('passed', False), row.get('evidence', ''),
                                  row.get('judged')) for row in rows]
        if rows:
            grade.counted_rows = [row['name'] for row in rows if row.get('counted', True)]
        return grade


def verdicts_text(grade):
    """'5 passed, 1 failed, 1 not judged'."""
    found = grade.verdicts()
    return '%d passed, %d failed, %d not judged' % tuple(len(found[v]) for v in VERDICTS)


def rows_text(grade):
    """'Course rubric rows counted (5): 3 passed, 1 failed, 1 not judged; stand out: 1 of 2.',
    or '' when no row is counted."""
    if not grade.course_rows:
        return ''
    required, stand_out = grade.row_verdicts(), grade.row_verdicts(stand_out=True)
    counted = sum(len(names) for names in required.values())
    parts = []
    if counted:
        parts.append('Course rubric rows counted (%d): %d passed, %d failed, %d not judged'
                     % ((counted,) + tuple(len(required[v]) for v in VERDICTS)))
    suggestions = sum(len(names) for names in stand_out.values())
    if suggestions:
        parts.append('stand out: %d of %d' % (len(stand_out[PASS]), suggestions))
    return ('; '.join(parts) + '.') if parts else ''


def wall_time_text(grade):
    """'14.2 s (build 3.1 s, rubric run 10.5 s)', or '' when the grade was not timed."""
    times = grade.wall_time
    if 'total' not in times:
        return ''
    parts = ['%s %.1f s' % (label, times[key]) for key, label in (('build', 'build'),
                                                                 ('rubric_run', 'rubric run'))
             if key in times]
    return '%.1f s%s' % (times['total'], ' (%s)' % ', '.join(parts) if parts else '')


def write_whole(path, text):
    """Write path whole or not at all: a grade stopped (or killed) while it writes leaves the
    file as it was before, never half of it."""
    import tempfile
    folder = os.path.dirname(os.path.abspath(path))
    fd, part = tempfile.mkstemp(prefix='.%s.' % os.path.basename(path), dir=folder)
    try:
        with os.fdopen(fd, 'w', encoding='utf-8', newline='') as stream:
            stream.write(text)
        os.chmod(part, 0o644)
        os.replace(part, path)
    except BaseException:
        try:
            os.remove(part)
        except OSError:
            pass
        raise


def write_json(grade, path):
    write_whole(path, json.dumps(grade.as_json(), indent=2) + '\n')


# Every line break a Markdown renderer (or an editor showing report.md) may honour.
LINE_BREAKS = re.compile('\r\n|[\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029]')
# What makes Markdown of text on one line: escapes, code spans, inline HTML, links and images,
# table cells.
MARKUP = re.compile(r'([\\`<>\[\]|])')
BACKTICKS = re.compile('`+')


def _break_text(match):
    """A line break as an escape that shows it: \\n, \\r, \\u2028."""
    return ''.join({'\n': '\\n', '\r': '\\r'}.get(char, '\\u%04x' % ord(char))
                   for char in match.group(0))


def one_line(text):
    """text with each line break shown as an escape (\\n, \\r, \\u2028)."""
    return LINE_BREAKS.sub(_break_text, str(text))


def md_text(text):
    """text as one line of Markdown that shows it as it is: a line break shows as \\n, and
    nothing in it makes a heading, a table row, a link, HTML or code of what follows."""
    return MARKUP.sub(r'\\\1', LINE_BREAKS.sub(_break_text, str(text)))


def md_code(text):
    """text as an inline code span, its delimiters longer than any run of backticks in it."""
    text = one_line(text)
    fence = '`' * (max((len(run) for run in BACKTICKS.findall(text)), default=0) + 1)
    pad = ' ' if text.startswith('`') or text.endswith('`') else ''
    return '%s%s%s%s%s' % (fence, pad, text, pad, fence)


def md_fenced(text):
    """Lines of a fenced code block holding text, its fence longer than any run of backticks
    in it, each line break but its own newlines shown as an escape."""
    lines = [LINE_BREAKS.sub(_break_text, line) for line in str(text).split('\n')]
    longest = max((len(run) for line in lines for run in BACKTICKS.findall(line)), default=0)
    fence = '`' * max(3, longest + 1)
    return [fence] + lines + [fence]


VERDICT_CELLS = {PASS: 'PASS', FAIL: '**FAIL**', UNJUDGED: '*NOT JUDGED*'}
NOT_JUDGED_MEANS = ('NOT JUDGED: the grader could not observe the item (its evidence says why), '
                    'so it is neither passed nor failed; it is counted apart from the failures, '
                    'scores nothing, and is for a teacher to judge.')
# docs/teaching.md of the grader's own checkout, whose section on isolation says what the
# sandbox lets a submission see and do, and what it does not cover.
TEACHING_DOC = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                             *[os.pardir] * 6, 'docs', 'teaching.md'))
ISOLATION_SECTION = 'isolation-how-and-what-it-does-not-cover'


def isolation_line(isolation):
    """The report's one line on the sandbox: how the submission ran (the isolation text's first
    clause: bubblewrap and the uid, or none) and a link to what the sandbox covers; the whole
    text, with the limits, is grade.json's isolation."""
    how = isolation.split(';', 1)[0]
    return ('- isolation: %s; its limits are in grade.json, and what it covers is in '
            '[docs/teaching.md, "Isolation: how, and what it does not cover"](%s#%s)'
            % (md_text(how), TEACHING_DOC.replace(' ', '%20'), ISOLATION_SECTION))


def _cell(text):
    return md_text(text)


def trial_outcome(trial, reached='reached in', missed='not reached:'):
    """A trial's outcome in words: why it could not run, its time to the ball, or why it missed."""
    if trial.error:
        return 'could not run: %s' % trial.error
    if trial.reached:
        outcome = '%s %.1f s' % (reached, trial.time_to_ball)
        return outcome + (' (%s)' % trial.reason if trial.reason else '')
    return '%s %s' % (missed, trial.reason or 'no reason recorded')


def markdown(grade):
    """The report: a table with one line per rubric item, the trials, then each failure's log lines."""
    lines = (['# Go Chase It: %s' % md_text(os.path.basename(grade.submission.rstrip('/'))), '',
              'Submission: %s  ' % md_code(grade.submission)] + _graded_folder(grade) +
             ['Rubric items (%d): %s. Chase success rate: %.0f%% (%d of %d trials, seed %d).'
              % (len(ITEM_NAMES), verdicts_text(grade), 100 * grade.success_rate,
                 sum(t.reached for t in grade.trials), len(grade.trials), grade.seed)]
             + ([rows_text(grade)] if rows_text(grade) else []) + ['']
             + _wall_time(grade) +
             ['| item | what is checked | result | evidence |', '|---|---|---|---|'])
    for name in ITEM_NAMES:
        item = grade.item(name) or Item(name, False, 'not run')
        summary = item.evidence.split('\n', 1)[0]
        lines.append('| `%s` | %s | %s | %s |' % (name, _cell(DESCRIPTIONS[name]),
                                                  VERDICT_CELLS[item.verdict], _cell(summary)))
    if grade.verdicts()[UNJUDGED]:
        lines += ['', NOT_JUDGED_MEANS]
    for advice in grade.advisories:
        lines += ['', 'Advisory, not a rubric item: %s' % md_text(advice)]
    lines += _course_rows(grade)
    if grade.trials:
        lines += ['', '## Trials', '',
                  'Each trial places the robot and the ball (from the seed), with the whole ball '
                  'in the robot\'s camera view, and ends when the robot\'s outline comes within '
                  '%.2f m of the ball\'s surface (or pushes the ball) or at the time limit. '
                  '"closest" is the smallest gap between the two. Each trial starts '
                  'ball_chaser.launch afresh after the placement, so no node keeps state from the '
                  'one before.' % (grade.reach or 0.0), '',
                  '| trial | robot start (x, y, yaw) | ball (x, y) | outcome | closest | path |',
                  '|---|---|---|---|---|---|']
        for trial in grade.trials:
            outcome = trial_outcome(trial)
            closest = '%.2f m' % trial.closest if trial.closest is not None else '-'
            picture = '![trial %d](%s)' % (trial.index, md_text(trial.png)) if trial.png else ''
            lines.append('| %d | (%.2f, %.2f, %.2f) | (%.2f, %.2f) | %s | %s | %s |'
                         % (trial.index, *trial.robot, *trial.ball, _cell(outcome), closest, picture))
    if grade.world_png and not grade.trials:
        lines += ['', '## The world', '',
                  'No placement could be drawn (see `chase`). The world as flatsim simulates it: the '
                  'colliders that stop a robot at its working height, the ball, and the robot where '
                  'it stood.', '', '![the world](%s)' % md_text(grade.world_png)]
    details = [item for item in (grade.item(n) for n in ITEM_NAMES)
               if item is not None and '\n' in item.evidence]
    if details:
        lines += ['', '## Details']
        for item in details:
            first, rest = item.evidence.split('\n', 1)
            lines += ['', '### `%s`' % item.name, '', md_text(first), ''] + md_fenced(rest)
    if grade.notes or grade.isolation:
        lines += ['', '## Notes', '']
        if grade.isolation:
            lines.append(isolation_line(grade.isolation))
        lines += ['- %s' % md_text(note) for note in grade.notes]
    return '\n'.join(lines) + '\n'


def _course_rows(grade):
    """The table of the course's other rubric rows, each counted or not (--rubric); none for a
    grade that judged none (an older grader's)."""
    if not grade.course_rows:
        return []
    lines = ['', "## The course's other rubric rows", '',
             'Judged from the submission\'s files and what the run saw, as a reviewer would. '
             'Rows marked "not counted" are shown but left out of the grade line (`--rubric`); '
             'stand out rows are the rubric\'s suggestions, not requirements.', '',
             '| row | what the course asks | result | evidence |', '|---|---|---|---|']
    for row in grade.rows_in_order():
        result = VERDICT_CELLS[row.verdict]
        if row.name not in grade.counted_rows:
            result += ' (not counted)'
        lines.append('| `%s` | %s | %s | %s |' % (row.name, _cell(ROW_DESCRIPTIONS[row.name]), result,
                                                  _cell(row.evidence.split('\n', 1)[0])))
    return lines


def _wall_time(grade):
    text = wall_time_text(grade)
    if not text:
        return []
    shared = ('; the trials were shared among %d worlds' % grade.worlds) if grade.worlds > 1 else ''
    return ['Wall time: %s%s.' % (text, shared), '']


def _graded_folder(grade):
    if grade.folder == '.' and not grade.ignored:
        return []
    line = 'Graded folder: %s' % md_code(grade.folder)
    if grade.ignored:
        line += '; not graded: %s' % ', '.join(md_code(path) for path in grade.ignored)
    return [line + '  ']


def write_markdown(grade, path):
    write_whole(path, markdown(grade))
