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


def grade_variants(tmp_path_factory, names, trials=1, timeout=30, before=lambda: None, options=(),
                   written=None):
    """(the grade process, {submission: its JSON}, the report folder) for the named variants.

    before() runs once the submissions are written, just before the grader starts; options
    are more of grade's options; written, a list, gets the folder the submissions were
    written to.
    """
    folder = tmp_path_factory.mktemp('submissions')
    for name in names:
        variants.compose(name, folder)
    if written is not None:
        written.append(folder)
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


def tree_state(*tops):
    """{path: (mode, owner, content digest or link target)} of every file and folder under tops,
    to compare before and after a grade."""
    import hashlib
    import stat
    seen = {}
    for top in tops:
        for root, dirs, files in os.walk(top):
            dirs[:] = [name for name in dirs if name != '__pycache__']
            for name in dirs + files:
                path = os.path.join(root, name)
                info = os.lstat(path)
                digest = None
                if stat.S_ISLNK(info.st_mode):
                    digest = os.readlink(path)
                elif stat.S_ISREG(info.st_mode):
                    with open(path, 'rb') as stream:
                        digest = hashlib.sha256(stream.read()).hexdigest()
                seen[os.path.relpath(path, top) if len(tops) == 1 else path] = (
                    stat.filemode(info.st_mode), info.st_uid, digest)
    return seen


def changed(before, after):
    """The paths whose state differs between two tree_state()s."""
    return sorted(path for path in set(before) | set(after) if before.get(path) != after.get(path))
