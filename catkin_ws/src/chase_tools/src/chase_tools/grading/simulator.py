"""The simulator of a grading session: the grader's own, out of the submission's reach.

A submission's world.launch would start the simulator itself (gazebo_ros's
empty_world.launch includes flatsim's), as the submission's uid, inside its
sandbox: a world.launch could then start a simulator of its own making, and
every pose the grader judges by would be its word. So the grader starts the
simulator (launches.Launches.start_simulator), from what the launch asks of it
(launchread.py): the world file, copied by the sandbox and read as data
(worldcopy.py), and the simulator node's private parameters. It runs

  - in a sandbox of its own (bubblewrap, its own process namespace, the
    grader's workspace read-only, only its own folder writable), so that no
    process of the submission can see it, signal it or trace it;
  - as a uid of its own when the grader is root (SIMULATOR_UID_BASE, one per
    grading process, far from the submissions' uids), with no capabilities;
  - in the session's network namespace, where the submission's nodes reach
    it over ROS as they reach Gazebo.

In the submission's sandbox, the programs that would start a simulator
(flatsim's simulator node, gazebo_ros's gzserver and gazebo) are shown as a
stand-by script: the launch's node of that name runs, says that the grader's
simulator runs, and waits to be stopped. spawn_model and the other nodes run
as written and find the grader's simulator on the master.
"""
import os
import pwd

from chase_tools.grading.limits import Cgroups, Limits
from chase_tools.grading.sandbox import UID_BASE, Confinement
from chase_tools.grading.scratch import write_new

# Below the submissions' uids (sandbox.UID_BASE and up), above any account's; one per grading
# process, as sandbox_uid is.
SIMULATOR_UID_BASE = UID_BASE - (1 << 24)
# The programs that start a simulator, (package, node type), shown as STANDBY in the
# submission's sandbox.
STARTERS = (('flatsim', 'simulator'), ('gazebo_ros', 'gzserver'), ('gazebo_ros', 'gazebo'))
STANDBY = '''#!/bin/sh
# The grader runs the simulator of this session itself; this node of the submission's launch
# stands by until the launch ends.
echo "[grader] the grader runs the simulator: this node ($0) stands by"
exec sleep infinity
'''
SIMULATOR_USER = 'simulator'
NODE_NAME = 'flatsim'


def simulator_uid(pid=None):
    """A uid for the simulator of the grading process pid: unique among running graders, and
    no account's, nor any submission's."""
    uid = SIMULATOR_UID_BASE + (os.getpid() if pid is None else pid)
    while True:
        try:
            pwd.getpwuid(uid)
        except KeyError:
            return uid
        uid += 1 << 22          # past the largest pid_max, still below UID_BASE


def confinement(folder, submission, uid=None):
    """The simulator's Confinement: a uid of its own when the submission has one (the grader
    is root: uid, when the grader chose it), else the grader's own; passwd and group written to
    folder (the grader's).
    Bounded per process (address space, open files, file size), as a sandbox without a cgroup."""
    if submission.switch_user:
        uid = gid = uid if uid is not None else simulator_uid()
    else:
        uid, gid = submission.uid, submission.gid
    made = Confinement(uid, gid, submission.switch_user, Limits(),
                       Cgroups(why='the simulator is bounded per process'))
    made.passwd = os.path.join(folder, 'simulator_passwd')
    made.group = os.path.join(folder, 'simulator_group')
    write_new(made.passwd, 'root:x:0:0:root:/root:/usr/sbin/nologin\n'
                           '%s:x:%d:%d:the grader\'s simulator:/nonexistent:/bin/sh\n'
                           'nobody:x:65534:65534:nobody:/nonexistent:/usr/sbin/nologin\n'
              % (SIMULATOR_USER, uid, gid), mode=0o644)
    write_new(made.group, 'root:x:0:\n%s:x:%d:\nnogroup:x:65534:\n' % (SIMULATOR_USER, gid),
              mode=0o644)
    return made


def starter_paths():
    """Every path at which roslaunch or rosrun may find a program that starts a simulator."""
    import roslib.packages
    found = []
    for package, node_type in STARTERS:
        try:
            found += roslib.packages.find_node(package, node_type)
        except Exception:  # noqa: BLE001 - a package this workspace does not have
            continue
    return sorted({os.path.realpath(path) for path in found} | set(found))


def standby_overlays(folder):
    """{path: the stand-by script} for the submission's sandbox; the script is written to
    folder (the grader's, made here)."""
    os.makedirs(folder, mode=0o755, exist_ok=True)
    script = os.path.join(folder, 'standby')
    if not os.path.exists(script):
        write_new(script, STANDBY, mode=0o755)
    return {path: script for path in starter_paths()}


def make_readable(top):
    """The grader's copy of the world, readable by the simulator's uid (its files are the
    grader's: written 0600)."""
    for root, dirs, files in os.walk(top):
        for name in dirs:
            path = os.path.join(root, name)
            if not os.path.islink(path):
                os.chmod(path, 0o755)
        for name in files:
            path = os.path.join(root, name)
            if not os.path.islink(path):
                os.chmod(path, 0o644)
    if not os.path.islink(top):
        os.chmod(top, 0o755)
