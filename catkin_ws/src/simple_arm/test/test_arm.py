"""The lessons' node logic without ROS: the clamp, the sweep, uniform images, stillness,
and arm_mover's replies."""
import math

import pytest

from simple_arm.arm import (MAX_TARGET_ANGLE, MotionWatch, clamp_at_boundaries, is_uniform, sweep_angle,
                            too_large_to_track)


def test_clamp_warns_as_the_course_node_does():
    angles, warnings = clamp_at_boundaries((1.57, 1.57), [(0.0, 1.57), (0.0, 1.0)])
    assert angles == [1.57, 1.0]
    assert warnings == ['j2 is out of bounds, valid range (0.00,1.00), clamping to: 1.00']
    angles, warnings = clamp_at_boundaries((-0.5, 0.5), [(0.0, 1.57), (0.0, 1.0)])
    assert angles == [0.0, 0.5] and warnings[0].startswith('j1 is out of bounds')


def test_a_target_too_large_to_track_is_named():
    assert too_large_to_track((MAX_TARGET_ANGLE, -MAX_TARGET_ANGLE)) is None
    assert too_large_to_track((1e308, 0.5)) == 'j1=1e+308: too large to track, the limit is 1e+06 rad either way'
    assert too_large_to_track((0.0, -1e308)).startswith('j2=-1e+308: too large')
    # Where the target is, a turn of the joint no longer changes target minus position.
    assert 1e308 - 2 * math.pi == 1e308
    assert MAX_TARGET_ANGLE - 1e-9 != MAX_TARGET_ANGLE


def test_sweep_is_a_ten_second_sine_on_whole_seconds():
    assert sweep_angle(0.0) == 0.0
    assert sweep_angle(2.9) == math.sin(2 * math.pi * 0.2) * math.pi / 2
    assert abs(sweep_angle(5.0)) < 1e-12


def test_uniform_means_every_byte_equals_the_first():
    assert is_uniform(bytes([178] * 30))
    assert not is_uniform(bytes([178] * 29 + [177]))


def test_motion_watch_is_still_only_within_the_tolerance():
    watch = MotionWatch()
    assert not watch.update((0.0, 0.0))
    assert watch.update((0.1, 0.0))
    assert not watch.update((0.1004, 0.0))
    assert watch.update((0.1004, 0.2))


def test_a_shutdown_mid_move_is_a_service_error_without_a_traceback(monkeypatch):
    import rospy
    from simple_arm.nodes import arm_mover
    from simple_arm.srv import GoToPositionRequest

    def interrupted(_seconds):
        raise rospy.ROSInterruptException('ROS shutdown request')
    monkeypatch.setattr(rospy, 'sleep', interrupted)
    monkeypatch.setattr(rospy, 'get_param', lambda _name, default=None: default)
    mover = arm_mover.ArmMover.__new__(arm_mover.ArmMover)
    mover.publishers = []
    # rospy logs a ServiceException's message alone; any other exception with its traceback.
    with pytest.raises(rospy.ServiceException, match='shut down before the arm settled'):
        mover.handle_safe_move(GoToPositionRequest(joint_1=0.0, joint_2=0.0))
