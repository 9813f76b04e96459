"""The processes of a submission's sandboxes, seen from outside them: found by uid or as a
sandbox's children, named, and killed when a sandbox ends.

Pure: reads /proc, sends signals; no ROS.
"""
import os
import signal

from chase_tools.grading.sandbox import USERNS_LAYER


def processes_of(uid, proc='/proc'):
    """[(pid, name)] of every process whose real uid is uid."""
    found = []
    for entry in os.listdir(proc):
        if not entry.isdigit():
            continue
        try:
            with open(os.path.join(proc, entry, 'status')) as stream:
                status = dict(line.rstrip('\n').split(':\t', 1) for line in stream if ':\t' in line)
        except (OSError, ValueError):
            continue
        if int(status.get('Uid', '-1\t').split()[0]) == uid:
            found.append((int(entry), status.get('Name', '?')))
    return sorted(found)


def kill_processes_of(uid):
    """SIGKILL every process of uid (a uid of the submission's own only); their names."""
    killed = processes_of(uid)
    for pid, _name in killed:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return [name for _pid, name in killed]


def end_sandbox(confinement):
    """SIGKILL whatever of the submission still runs (its cgroup's processes, and its uid's
    when the uid is its own); the names of the processes its uid still had."""
    if confinement.cgroups.active:
        confinement.cgroups.kill_all()
    return kill_processes_of(confinement.uid) if confinement.own_uid else []


def sandbox_children(pid):
    """The processes a sandbox started at its top (pids seen from here), oldest first: the
    command, then whatever a process of it left behind when it detached from its parent."""
    inits = child_pids(pid)
    found = []
    for init in inits:
        found += sorted(child_pids(init), key=_start_time)
    if found and _is_userns_layer(found[0]):
        # The command runs under the second bwrap, which closes user namespaces.
        found = child_pids(found[0])[:1] + found[1:]
    return found


def _is_userns_layer(pid):
    try:
        with open('/proc/%d/cmdline' % pid, 'rb') as stream:
            args = stream.read().split(b'\0')
    except OSError:
        return False
    layer = [arg.encode() for arg in USERNS_LAYER]
    return args[1:1 + len(layer)] == layer


def child_pids(pid):
    try:
        with open('/proc/%d/task/%d/children' % (pid, pid)) as stream:
            return [int(child) for child in stream.read().split()]
    except OSError:
        return []


def _start_time(pid):
    try:
        with open('/proc/%d/stat' % pid) as stream:
            return int(stream.read().rsplit(')', 1)[1].split()[19])
    except (OSError, IndexError, ValueError):
        return 0


def process_name(pid):
    try:
        with open('/proc/%d/comm' % pid) as stream:
            return stream.read().strip()
    except OSError:
        return '?'
