"""What the grader's end-to-end tests share: one `grade` run over a folder of fixture submissions.

A test module grades its submissions once, two at a time, and each test reads
what the grader wrote for one of them.
"""
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402

GRADE_TIMEOUT_S = 1500


def grade_variants(tmp_path_factory, names, trials=1, timeout=30, before=lambda: None, options=()):
    """(the grade process, {submission: its JSON}, the report folder) for the named variants.

    before() runs once the submissions are written, just before the grader starts; options
    are more of grade's options.
    """
    folder = tmp_path_factory.mktemp('submissions')
    for name in names:
        variants.compose(name, folder)
    before()
    out = tmp_path_factory.mktemp('graded')
    # One submission is graded as itself, into the folder a folder of them would give it.
    one = len(names) == 1
    proc = subprocess.run(['grade', str(folder / names[0] if one else folder), '--trials', str(trials),
                           '--timeout', str(timeout), '--jobs', '2',
                           '--output', str(out / 'report' / names[0] if one else out / 'report'),
                           '--json', str(out / 'all.json')] + list(options),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=GRADE_TIMEOUT_S, check=False)
    with open(out / 'all.json') as stream:
        data = json.load(stream)
    results = ({names[0]: data} if one else {entry['name']: entry for entry in data['submissions']})
    return proc, results, out / 'report'


def items(results, name):
    return {item['name']: item for item in results[name]['items']}


def failed(results, name):
    return sorted(item['name'] for item in results[name]['items'] if not item['passed'])


def report_of(graded, name):
    with open(os.path.join(graded[2], name, 'report.md')) as stream:
        return stream.read()


def processes_of_uid(uid):
    """The pids (as /proc names) of every process running as uid."""
    found = []
    for entry in os.listdir('/proc'):
        try:
            with open('/proc/%s/status' % entry) as stream:
                if re.search(r'^Uid:\s+%d\s' % uid, stream.read(), re.M):
                    found.append(entry)
        except OSError:
            continue
    return found
