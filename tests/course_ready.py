"""Wait until a ROS graph shows something, for tests that start ROS from a shell:

    python course_ready.py node|service|publisher|subscriber NAME TIMEOUT_S
    python course_ready.py within MODEL OTHER METRES TIMEOUT_S

Exits 0 once the master at ROS_MASTER_URI has it (or once MODEL's origin is within
METRES of OTHER's in the plane), 1 with a message after TIMEOUT_S.
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


def gap(get_state, model, other):
    a, b = (get_state(model_name=name).pose.position for name in (model, other))
    return ((a.x - b.x) ** 2 + (a.y - b.y) ** 2) ** 0.5


def wait_within(model, other, metres, timeout):
    import rospy
    from gazebo_msgs.srv import GetModelState
    rospy.init_node('course_ready', anonymous=True, disable_signals=True)
    get_state = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)
    start = gap(get_state, model, other)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        now = gap(get_state, model, other)
        if now <= metres:
            print('%s came from %.2f m to %.2f m of %s' % (model, start, now, other))
            return
        time.sleep(0.2)
    sys.exit('%s stayed %.2f m from %s (%.2f m at the start) for %g s' % (model, now, other, start, timeout))


def main(argv):
    if len(argv) == 5 and argv[0] == 'within':
        wait_within(argv[1], argv[2], float(argv[3]), float(argv[4]))
        return
    if len(argv) != 3 or argv[0] not in ('node', 'service', 'publisher', 'subscriber'):
        sys.exit('usage: course_ready.py node|service|publisher|subscriber NAME TIMEOUT_S\n'
                 '       course_ready.py within MODEL OTHER METRES TIMEOUT_S')
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
