"""Commands that start processes stop all of them on SIGTERM and SIGHUP, as on Ctrl-C."""
import os
import pathlib
import shutil
import signal
import subprocess
import sys

import pytest

from rosproc import free_port, wait_until

SUBMISSIONS = (pathlib.Path(__file__).resolve().parent.parent / 'catkin_ws' / 'src' / 'chase_tools' / 'test'
               / 'fixtures' / 'submissions')


def descendants(root):
    """{pid: command line} of every live process below root."""
    children = {}
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            with open('/proc/%s/stat' % entry) as stat:
                fields = stat.read().rpartition(')')[2].split()
            with open('/proc/%s/cmdline' % entry, 'rb') as cmdline:
                command = cmdline.read().replace(b'\0', b' ').decode(errors='replace')
        except OSError:
            continue
        if fields[0] != 'Z':
            children.setdefault(int(fields[1]), []).append((int(entry), command))
    found, todo = {}, [root]
    while todo:
        for pid, command in children.get(todo.pop(), []):
            found[pid] = command
            todo.append(pid)
    return found


def alive(pid):
    try:
        with open('/proc/%d/stat' % pid) as stat:
            return stat.read().rpartition(')')[2].split()[0] != 'Z'
    except OSError:
        return False


def assert_a_signal_stops_everything(proc, signum, start_timeout):
    """Once the chaser's node runs under proc (so the master, roslaunch and the world run too),
    send signum: proc must exit as on Ctrl-C and leave none of its processes behind."""
    try:
        started = wait_until(lambda: (lambda found: found if any('process_image' in c for c in found.values())
                                      else None)(descendants(proc.pid)), start_timeout)
        assert started, 'the chaser never started'
        proc.send_signal(signum)
        output, _ = proc.communicate(timeout=90)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, output
    left = {pid: command for pid, command in started.items()
            if alive(pid) and not wait_until(lambda: not alive(pid), 5.0)}
    assert not left, 'left behind: %s' % left


@pytest.mark.parametrize('signum', [signal.SIGTERM, signal.SIGHUP])
def test_evaluate_stops_every_process_it_started(tmp_path, signum):
    code = 'from chase_tools.evaluate import main; raise SystemExit(main())'
    proc = subprocess.Popen([sys.executable, '-c', code, '--trials', '1', '--modes', 'course', '--jobs', '1',
                             '--base-port', str(free_port()), '--log-dir', str(tmp_path)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert_a_signal_stops_everything(proc, signum, 120.0)


@pytest.mark.skipif(shutil.which('bwrap') is None, reason='the grader needs bubblewrap')
def test_grade_stops_every_process_it_started(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(SUBMISSIONS))
    import variants
    folder = tmp_path / 'submissions'
    variants.compose('py_correct', folder)
    proc = subprocess.Popen(['grade', str(folder), '--trials', '1', '--output', str(tmp_path / 'report')],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    # A folder: grade runs one grader per submission, which builds, then launches the chase.
    assert_a_signal_stops_everything(proc, signal.SIGTERM, 240.0)
