"""flatsim.ros.lockstep without ROS: the adaptive bound and holds, on a fake wall clock."""
import threading
import time

import pytest

from flatsim.errors import FlatsimError
from flatsim.ros.lockstep import (LEARNING_QUIET_FACTOR, MARGIN, TRUST_FRAMES, WHOLE_ANSWER_MAX_S, Lockstep,
                                  ReactionBound)


def test_a_new_controller_is_waited_for_up_to_the_longest_wait():
    assert ReactionBound(max_wait=2.0).bound() == 2.0


def test_a_controller_that_answers_every_frame_keeps_the_longest_wait():
    bound = ReactionBound(max_wait=2.0)
    for _ in range(3 * TRUST_FRAMES):
        bound.record(0.004)
    assert bound.bound() == 2.0


def test_one_silent_frame_shortens_the_wait_to_a_few_usual_reaction_times():
    bound = ReactionBound(max_wait=2.0, min_wait=0.001)
    for reaction in [0.004] * 20 + [0.010]:
        bound.record(reaction)
    bound.record(None)
    # p90 of twenty 4 ms and one 10 ms reaction is 4 ms.
    assert bound.bound() == pytest.approx(MARGIN * 0.004)


def test_a_controller_that_never_answered_costs_the_longest_wait_once_then_the_shortest():
    bound = ReactionBound(max_wait=2.0, min_wait=0.005)
    bound.record(None)
    assert bound.bound() == 0.005


def test_answering_every_frame_again_earns_the_longest_wait_back():
    bound = ReactionBound(max_wait=2.0, min_wait=0.001)
    bound.record(None)
    for _ in range(TRUST_FRAMES - 1):
        bound.record(0.003)
        assert bound.bound() < 2.0
    bound.record(0.003)
    assert bound.bound() == 2.0


def test_the_learned_wait_stays_within_its_limits():
    slow = ReactionBound(max_wait=0.5, min_wait=0.001)
    for reaction in [0.4] * 5 + [None]:
        slow.record(reaction)
    assert slow.bound() == 0.5
    fast = ReactionBound(max_wait=0.5, min_wait=0.01)
    for reaction in [0.0001] * 5 + [None]:
        fast.record(reaction)
    assert fast.bound() == 0.01


def test_bad_limits_are_refused():
    with pytest.raises(FlatsimError):
        ReactionBound(max_wait=0.1, min_wait=0.2)
    with pytest.raises(FlatsimError):
        Lockstep(max_wait=0.0)


class FakeClock:
    """A wall clock that advances only when told; Condition.wait still times out on real time."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_a_command_after_the_frame_ends_the_hold_and_its_reaction_time_is_learned():
    clock = FakeClock()
    lockstep = Lockstep(enabled=True, max_wait=30.0, clock=clock, quiet=0.0)
    lockstep.frame_sent('robot')
    clock.now += 0.004
    lockstep.command_arrived('robot')
    assert lockstep.hold() == {'robot': pytest.approx(0.004)}


def test_a_command_from_before_the_frame_is_not_its_answer():
    lockstep = Lockstep(enabled=True, max_wait=0.05, min_wait=0.01)
    lockstep.command_arrived('robot')
    lockstep.frame_sent('robot')
    assert lockstep.hold() == {'robot': None}


def test_a_command_from_another_thread_wakes_the_hold():
    lockstep = Lockstep(enabled=True, max_wait=30.0)
    lockstep.frame_sent('robot')
    threading.Timer(0.05, lockstep.command_arrived, args=('robot',)).start()
    started = time.monotonic()
    outcome = lockstep.hold()
    assert outcome['robot'] is not None
    assert time.monotonic() - started < 10.0


def test_a_silent_controller_is_waited_for_only_up_to_the_bound():
    lockstep = Lockstep(enabled=True, max_wait=0.05, min_wait=0.01)
    started = time.monotonic()
    assert (lockstep.frame_sent('robot'), lockstep.hold())[1] == {'robot': None}
    assert time.monotonic() - started >= 0.05
    # Now known to be silent now and then, and never to have answered: the shortest wait.
    assert lockstep.bound_for('robot').bound() == 0.01


def test_controllers_started_afresh_are_waited_for_as_new_ones():
    """A node started again answers its first frame cold: what the one before it did (a silent
    frame) must not cut the wait for it to the shortest."""
    lockstep = Lockstep(enabled=True, max_wait=0.05, min_wait=0.01)
    lockstep.frame_sent('robot')
    assert lockstep.hold() == {'robot': None}
    assert lockstep.bound_for('robot').bound() == 0.01
    lockstep.new_controllers()
    assert lockstep.bound_for('robot').bound() == 0.05


@pytest.mark.parametrize('end_hold', ['interrupt', 'forget'])
def test_a_reset_or_deleted_robot_ends_a_hold_at_once(end_hold):
    lockstep = Lockstep(enabled=True, max_wait=30.0)
    lockstep.frame_sent('robot')
    if end_hold == 'interrupt':
        threading.Timer(0.05, lockstep.interrupt).start()
    else:
        threading.Timer(0.05, lockstep.forget, args=('robot',)).start()
    started = time.monotonic()
    assert lockstep.hold() == {}
    assert time.monotonic() - started < 10.0


def test_each_robot_waits_for_its_own_controller():
    lockstep = Lockstep(enabled=True, max_wait=0.05, min_wait=0.01)
    lockstep.frame_sent('a')
    lockstep.frame_sent('b')
    lockstep.command_arrived('b')
    outcome = lockstep.hold()
    assert outcome['a'] is None and outcome['b'] is not None


def test_settle_returns_once_the_pending_frame_is_answered():
    lockstep = Lockstep(enabled=True, max_wait=30.0)
    lockstep.frame_sent('robot')
    holder = threading.Thread(target=lockstep.hold)
    holder.start()
    threading.Timer(0.05, lockstep.command_arrived, args=('robot',)).start()
    assert lockstep.settle(wall_timeout=20.0)
    holder.join()


def test_settle_gives_up_at_its_timeout_and_returns_at_once_with_nothing_pending():
    lockstep = Lockstep(enabled=True, max_wait=30.0)
    assert lockstep.settle(wall_timeout=0.0)
    lockstep.frame_sent('robot')
    assert not lockstep.settle(wall_timeout=0.05)


def test_the_hold_goes_on_while_the_frame_s_commands_follow_each_other():
    # A node that sends "move" and then "stop" from one callback, 20 ms apart: the hold ends
    # after the stop, so the stop is in effect when time runs on.
    lockstep = Lockstep(enabled=True, max_wait=30.0, quiet=0.1)
    sent = time.monotonic()
    lockstep.frame_sent('robot')
    moved, stopped = [], []

    def stop():
        stopped.append(time.monotonic())
        lockstep.command_arrived('robot')

    def move():
        # The stop is timed from the move, so that a timer late on a loaded machine delays both.
        moved.append(time.monotonic())
        lockstep.command_arrived('robot')
        threading.Timer(0.02, stop).start()
    threading.Timer(0.02, move).start()
    outcome = lockstep.hold()
    ended = time.monotonic()
    assert stopped and ended >= stopped[0]
    # Its reaction time is that of the first command, not the last.
    assert outcome['robot'] == pytest.approx(moved[0] - sent, abs=0.01)


def test_a_hold_that_commands_keep_up_ends_soon_after_the_first():
    lockstep = Lockstep(enabled=True, max_wait=30.0, quiet=0.1)
    lockstep.frame_sent('robot')
    keep_up = threading.Event()

    def send():
        while not keep_up.is_set():
            lockstep.command_arrived('robot')
            time.sleep(0.01)
    sender = threading.Thread(target=send)
    sender.start()
    try:
        started = time.monotonic()
        assert lockstep.hold()['robot'] is not None
        assert time.monotonic() - started < 10.0 < lockstep.max_wait
    finally:
        keep_up.set()
        sender.join()


def test_an_interrupt_ends_the_quiet_time_at_once():
    lockstep = Lockstep(enabled=True, max_wait=30.0, quiet=20.0)
    lockstep.frame_sent('robot')
    lockstep.command_arrived('robot')
    threading.Timer(0.05, lockstep.interrupt).start()
    started = time.monotonic()
    assert lockstep.hold() == {}
    assert time.monotonic() - started < 10.0


def test_a_quiet_time_beyond_the_longest_wait_is_refused():
    with pytest.raises(FlatsimError, match='quiet time'):
        Lockstep(max_wait=1.0, quiet=2.0)


def a_frame_answered_once(quiet=0.005):
    """(lockstep, clock) just after a hold: its frame answered 4 ms after it went out, then
    nothing for a new controller's quiet time."""
    clock = FakeClock()
    lockstep = Lockstep(enabled=True, max_wait=30.0, clock=clock, quiet=quiet)
    lockstep.frame_sent('robot')
    clock.now += 0.004
    lockstep.command_arrived('robot')
    clock.now += LEARNING_QUIET_FACTOR * quiet
    lockstep.hold()
    return lockstep, clock


def test_a_follow_up_after_the_hold_teaches_the_next_holds_to_wait_for_it():
    # A rospy node that calls the service twice from one callback: its stop comes 20 ms after
    # its move, past a 1 ms quiet time (10 ms while it is new). That follow-up, before the next
    # frame, is learned.
    lockstep, clock = a_frame_answered_once(quiet=0.001)
    clock.now += 0.010
    lockstep.command_arrived('robot')     # the stop, 20 ms after the move
    assert lockstep.quiet_for('robot').quiet() == pytest.approx(0.04)
    # A command after the next frame is its answer, not a follow-up; nor is one 100 ms later.
    lockstep.frame_sent('robot')
    clock.now += 0.1
    lockstep.command_arrived('robot')
    assert lockstep.quiet_for('robot').quiet() == pytest.approx(0.04)


def test_a_controller_on_a_timer_of_its_own_does_not_stretch_the_holds():
    lockstep, clock = a_frame_answered_once()
    for _ in range(5):      # it publishes every 100 ms whatever the frames do
        clock.now += 0.1
        lockstep.command_arrived('robot')
    assert lockstep.quiet_for('robot').quiet() == 0.005


def answered_alike(lockstep, clock, commands, frames=TRUST_FRAMES):
    """Each of `frames` frames answered with `commands` commands 2 ms apart, then nothing for
    longer than any hold waits, so that each returns at once. An answer's size is known once
    the next frame goes out."""
    for _ in range(frames):
        lockstep.frame_sent('robot')
        for _ in range(commands):
            clock.now += 0.002
            lockstep.command_arrived('robot')
        clock.now += WHOLE_ANSWER_MAX_S
        lockstep.hold()


def moved_after_moves_and_stops(quiet):
    """A Lockstep on the wall clock whose controller answered each of its last frames with a
    move and a stop, and has just sent the move answering its next frame."""
    lockstep = Lockstep(enabled=True, max_wait=30.0, quiet=quiet)
    for _ in range(TRUST_FRAMES):
        lockstep.frame_sent('robot')
        lockstep.command_arrived('robot')
        lockstep.command_arrived('robot')
        lockstep.hold()
    lockstep.frame_sent('robot')
    lockstep.command_arrived('robot')
    return lockstep


def test_a_move_and_stop_sent_alike_each_frame_are_waited_for_however_far_apart():
    # A rospy node that calls the service twice from each callback, its two calls normally
    # a moment apart. Once the machine is loaded, one stop comes 60 ms after its move, well
    # past the quiet time: time must still run on with the stop in effect.
    lockstep = moved_after_moves_and_stops(quiet=0.01)
    threading.Timer(0.06, lockstep.command_arrived, args=('robot',)).start()
    assert lockstep.hold()['robot'] is not None
    assert lockstep._commands['robot'] == 2 * (TRUST_FRAMES + 1), 'time ran on with the move in effect'


def test_an_answer_of_as_many_commands_as_usual_ends_the_hold_without_a_quiet_time():
    clock = FakeClock()
    lockstep = Lockstep(enabled=True, max_wait=30.0, clock=clock, quiet=0.5)
    answered_alike(lockstep, clock, commands=1)
    lockstep.frame_sent('robot')
    clock.now += 0.002
    lockstep.command_arrived('robot')
    # The fake clock stands still: a hold that waited for a quiet time would never end.
    holder = threading.Thread(target=lockstep.hold)
    holder.start()
    holder.join(timeout=5.0)
    ended = not holder.is_alive()
    lockstep.interrupt()
    holder.join()
    assert ended, 'the hold waited for a quiet time after the usual single command'


def test_answers_that_differ_in_size_are_held_by_the_quiet_time():
    clock = FakeClock()
    lockstep = Lockstep(enabled=True, max_wait=30.0, clock=clock, quiet=0.01)
    answered_alike(lockstep, clock, commands=2, frames=TRUST_FRAMES - 1)
    assert lockstep.commands_per_answer('robot') is None      # not yet seen often enough
    answered_alike(lockstep, clock, commands=2, frames=2)
    assert lockstep.commands_per_answer('robot') == 2
    answered_alike(lockstep, clock, commands=1, frames=2)
    assert lockstep.commands_per_answer('robot') is None


def test_a_new_controller_s_stop_that_comes_late_is_waited_for():
    # A node started afresh on a loaded machine: its first stop comes 45 ms after its move, past
    # the 10 ms quiet time. Nothing is known of its answers yet, so the hold waits for it.
    lockstep = Lockstep(enabled=True, max_wait=30.0, quiet=0.01)
    lockstep.frame_sent('robot')
    lockstep.command_arrived('robot')
    threading.Timer(0.045, lockstep.command_arrived, args=('robot',)).start()
    assert lockstep.hold()['robot'] is not None
    assert lockstep._commands['robot'] == 2, 'time ran on with the move in effect'


def test_a_usual_answer_that_stays_short_is_waited_for_a_bounded_time():
    lockstep = moved_after_moves_and_stops(quiet=0.0)     # and no stop comes this time
    started = time.monotonic()
    assert lockstep.hold()['robot'] is not None
    assert WHOLE_ANSWER_MAX_S - 0.01 <= time.monotonic() - started < 10.0


def test_controllers_started_afresh_are_not_expected_to_answer_as_the_old_ones_did():
    clock = FakeClock()
    lockstep = Lockstep(enabled=True, max_wait=30.0, clock=clock, quiet=0.01)
    answered_alike(lockstep, clock, commands=2, frames=TRUST_FRAMES + 1)
    assert lockstep.commands_per_answer('robot') == 2
    lockstep.new_controllers()
    assert lockstep.commands_per_answer('robot') is None
