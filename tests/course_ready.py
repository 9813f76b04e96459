"""Wait until a ROS graph shows something, for tests that start ROS from a shell:

    python course_ready.py node|service|publisher|subscriber NAME TIMEOUT_S

Exits 0 once the master at ROS_MASTER_URI has it, 1 with a message after TIMEOUT_S.
"""
import sys
import time

import rosgraph


def present(master, kind, name):
    if kind == 'node':
        master.lookupNode(name)
        return True
    if kind == 'service':
        master.lookupService(name)
        return True
    publishers, subscribers, _services = master.getSystemState()
    table = dict(publishers if kind == 'publisher' else subscribers)
    return bool(table.get(name))


def main(argv):
    if len(argv) != 3 or argv[0] not in ('node', 'service', 'publisher', 'subscriber'):
        sys.exit('usage: course_ready.py node|service|publisher|subscriber NAME TIMEOUT_S')
    kind, name, timeout = argv[0], argv[1], float(argv[2])
    master = rosgraph.Master('/course_ready')
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if present(master, kind, name):
                return
        except (OSError, rosgraph.MasterError):
            pass
        time.sleep(0.2)
    sys.exit('no %s %s on %s within %g s' % (kind, name, rosgraph.get_master_uri(), timeout))


if __name__ == '__main__':
    main(sys.argv[1:])
