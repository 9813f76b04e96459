"""The rubric run's bounds: how long it waits for what (wall and sim seconds), and how much it
keeps of what a submission can send as fast as it likes.

The grader's overall bound on a run (run_wall_bound) is the sum of its steps' own.
"""
from chase_tools.grading import probe

REACT_S = 1.0                  # sim time the node gets to react to the ball's going
WATCH_S = 2.0                  # sim time the robot must then stay still
STOP_GRACE_S = 3.0

# Wall seconds between looks at something the run waits for (the master, the world, a service).
POLL_S = 0.05
# flatsim's ~model_states_rate when the launch does not set it (Hz of sim time).
DEFAULT_STATES_RATE = 50.0
# Wall seconds an extra world's chaser has to answer for the first time (TrialWorld.warm_up).
WARM_UP_S = 10.0
# Sim seconds a state's counted time may differ from the grader's /clock when it came.
STATES_CLOCK_TOLERANCE_S = 1.0
# Sim seconds at the start of a trial during which the camera's frames are checked for the ball.
FRAME_WATCH_S = 2.0
WORLD_COPY_S = 60.0            # wall seconds for the sandbox to copy the world (worldcopy.py)
LAUNCH_READ_S = 60.0           # wall seconds for the sandbox to read the world's launch (launchread.py)
WORLD_COPY_LOG = 64 << 10
# What the grader keeps of what a submission can send as fast as it likes (trials.RollingLog):
# commands on /cmd_vel, process_image's calls, and the model states of a trial (50 Hz of sim
# time by default, 3000 in a 60 s trial). Memory stays bounded however much comes.
COMMANDS_KEPT = 20000
CALLS_KEPT = 20000
STATES_KEPT = 30000
# Model states waiting for the grader's callback. rospy deserializes what one read of the socket
# holds (64 KiB) into that queue, dropping the oldest beyond it, then calls back for each on the
# connection's own thread: a flatsim state of a few models takes some 500 bytes, so no state of
# the simulator's is dropped (the trials count them, trials.state_times), and a flood of small
# messages on another connection is bounded all the same.
STATES_QUEUE = 256
# Wall seconds the guard waits for a node to say where it takes connections.
NODE_ANSWER_S = 2.0
# Wall seconds drive_bot has to answer a call of the grader's, or one it forwards.
DRIVE_CALL_S = 10.0
FORWARD_S = 10.0
# setuptools' stand-in for distutils, which the venv puts first, costs every roslaunch and
# xacro about 0.2 s of imports (rosclean asks for distutils); the standard library's does
# the same job for them.
QUICK_START = {'SETUPTOOLS_USE_DISTUTILS': 'stdlib'}
# The grader's simulator's record of the messages it refused, in its own folder.
SIMULATOR_REFUSALS = 'refused_messages.json'
# Wall seconds between the watch's looks at the master and at this node (node.GraderNode.watch).
WATCH_EVERY_S = 0.5


# Wall seconds the robot has to be commanded to set off in the stop check (5 s of sim time).
SET_OFF_WALL_S = 120.0
# Wall seconds sensors has to see an image and a scan, and lockstep its connections.
SENSORS_WALL_S = 30.0
LOCKSTEP_WALL_S = 10.0
# Wall seconds the grader's simulator waits, under lockstep, for a new controller or one that
# has answered every frame so far (its ~lockstep_max_wait; flatsim's own default is 1 s): nodes
# started afresh for a trial answer their first frame cold, which on a loaded machine took over
# a second, and the trial then ran on a frame late.
LOCKSTEP_MAX_WAIT_S = 5.0
# Wall seconds the grader's /cmd_vel subscriber has to connect to the nodes' publishers.
CMD_PUBLISHERS_WALL_S = 5.0


def sim_wall_s(sim_seconds):
    """Wall seconds the grader waits for sim_seconds of sim time before it counts as stalled:
    lockstep can make sim time far slower than the wall's when the nodes are slow."""
    return 60.0 + 20.0 * sim_seconds


def fresh_start_wall_s(chaser_timeout=30.0):
    """Wall seconds ball_chaser.launch may take to be started afresh before a trial or the stop
    check (Chaser.start_chaser_afresh): stopped, its service waited for, the grader's and the
    simulator's connections to its nodes waited for."""
    return STOP_GRACE_S + chaser_timeout + probe.HEADER_PROBE_S + CMD_PUBLISHERS_WALL_S + LOCKSTEP_WALL_S


def run_wall_bound(trials, timeout, world_timeout=120.0, chaser_timeout=30.0):
    """Wall seconds the rubric run can take with every step as slow as the session lets it be:
    the sum of each step's own bound. The world and ball_chaser.launch come up at most three
    times (its first start, and two starts again when the guess of drive_bot was wrong or its
    service is not the course's), each within its bound and a last look at its service; drive_bot
    is called four times; each trial, and the stop check's three waits, within their wall bounds,
    each after ball_chaser.launch is started afresh within its own."""
    bring_up = (3 * (world_timeout + chaser_timeout + probe.HEADER_PROBE_S) + 4 * DRIVE_CALL_S
                + SENSORS_WALL_S + LOCKSTEP_WALL_S)
    stop_check = SET_OFF_WALL_S + sim_wall_s(0.5) + sim_wall_s(REACT_S + WATCH_S)
    # Each trial and the stop check start ball_chaser.launch afresh.
    fresh = fresh_start_wall_s(chaser_timeout)
    return bring_up + max(trials, 1) * (sim_wall_s(timeout) + fresh) + stop_check + fresh
