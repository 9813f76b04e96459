"""Controllers and the command gate, from detections on synthetic frames."""
import pytest

from ball_chaser.control import STOP, CommandGate, CourseController, DriveCommand, ProportionalController
from ball_chaser.detect import BallDetection, find_ball, image_msg_to_array
from ball_chaser_frames import encode, rgb_scene

WIDTH, HEIGHT = 300, 200


def detection_at(column, radius=10, width=WIDTH, height=HEIGHT, encoding='rgb8'):
    centre = None if column is None else (column, height // 3)
    message = encode(rgb_scene(width, height, ball_centre=centre, radius=radius), encoding, padding=2)
    return find_ball(image_msg_to_array(message), encoding)


@pytest.mark.parametrize('encoding', ['rgb8', 'bgra8', 'mono8'])
@pytest.mark.parametrize('column, expected', [
    (40, DriveCommand(0.0, 0.5)),
    (150, DriveCommand(0.5, 0.0)),
    (260, DriveCommand(0.0, -0.5)),
    (None, STOP),
])
def test_course_controller_turns_toward_the_third_holding_the_ball(encoding, column, expected):
    controller = CourseController(forward_speed=0.5, turn_speed=0.5)
    assert controller.command(detection_at(column, encoding=encoding)) == expected


@pytest.mark.parametrize('column, expected', [
    (99.9, DriveCommand(0.0, 0.3)),
    (100.0, DriveCommand(0.2, 0.0)),
    (199.9, DriveCommand(0.2, 0.0)),
    (200.0, DriveCommand(0.0, -0.3)),
])
def test_course_controller_third_boundaries(column, expected):
    detection = BallDetection(WIDTH, HEIGHT, 1, centroid_column=column)
    assert CourseController(forward_speed=0.2, turn_speed=0.3).command(detection) == expected


def test_course_controller_follows_a_ball_partly_out_of_frame():
    assert CourseController().command(detection_at(-5)).angular_z > 0
    assert CourseController().command(detection_at(WIDTH + 5)).angular_z < 0


def proportional(**overrides):
    settings = dict(max_linear_x=0.5, steering_gain=1.5, max_angular_z=1.0,
                    stop_width_fraction=0.3, stop_area_fraction=0.1, search_turn=0.0)
    settings.update(overrides)
    return ProportionalController(**settings)


def test_proportional_drives_straight_at_a_centred_ball():
    detection = detection_at((WIDTH - 1) / 2.0, radius=15)
    command = proportional().command(detection)
    assert detection.bounding_width == 30, 'a disc centred between two columns spans an even count'
    assert command.angular_z == 0.0
    assert command.linear_x == pytest.approx(0.5 * (1 - (30 / WIDTH) / 0.3))


@pytest.mark.parametrize('column', [80, 100, 200, 220])
def test_proportional_steers_by_the_offset(column):
    detection = detection_at(column)
    offset = (column - (WIDTH - 1) / 2.0) / (WIDTH / 2.0)
    command = proportional().command(detection)
    assert command.angular_z == pytest.approx(-1.5 * offset)
    assert command.linear_x == pytest.approx(0.5 * (1 - (21 / WIDTH) / 0.3) * (1 - abs(offset)))


def test_proportional_turn_rate_is_capped():
    command = proportional(steering_gain=10.0).command(detection_at(5))
    assert command.angular_z == 1.0


def test_proportional_slows_down_as_the_ball_grows():
    speeds = [proportional().command(detection_at(WIDTH // 2, radius=r)).linear_x for r in (5, 15, 30, 40)]
    assert speeds == sorted(speeds, reverse=True)
    assert speeds[0] > speeds[-1] > 0


def test_proportional_stops_driving_when_the_ball_is_wide_but_keeps_centring_it():
    close = detection_at(100, radius=50)
    assert close.width_fraction >= 0.3
    command = proportional(stop_area_fraction=1.0).command(close)
    assert command.linear_x == 0.0
    assert command.angular_z > 0


def test_proportional_stops_driving_when_the_ball_covers_enough_area():
    detection = detection_at((WIDTH - 1) / 2.0, radius=20)
    assert detection.width_fraction < 0.3 and detection.area_fraction > 0.02
    assert proportional(stop_area_fraction=0.02).command(detection) == STOP
    assert proportional(stop_area_fraction=0.5).command(detection).linear_x > 0


def test_proportional_stops_when_there_is_no_ball():
    assert proportional().command(detection_at(None)) == STOP


def test_proportional_searches_toward_where_the_ball_was_last_seen():
    controller = proportional(search_turn=0.4)
    assert controller.command(detection_at(None)) == DriveCommand(0.0, 0.4)
    controller.command(detection_at(260))
    assert controller.command(detection_at(None)) == DriveCommand(0.0, -0.4)
    controller.command(detection_at(20))
    assert controller.command(detection_at(None)) == DriveCommand(0.0, 0.4)


def test_proportional_turns_in_place_toward_a_ball_at_the_edge():
    command = proportional().command(detection_at(-3))
    assert command.linear_x == pytest.approx(0.0, abs=0.02)
    assert command.angular_z > 1.0 - 1e-9


@pytest.mark.parametrize('name, value', [('stop_width_fraction', 0.0), ('stop_area_fraction', 1.5),
                                         ('max_linear_x', -1.0), ('search_turn', float('nan'))])
def test_proportional_settings_are_checked(name, value):
    with pytest.raises(ValueError, match=name):
        proportional(**{name: value})


def test_gate_sends_the_first_command_and_then_only_meaningful_changes():
    gate = CommandGate(linear_deadband=0.02, angular_deadband=0.05)
    first = DriveCommand(0.3, 0.1)
    assert gate.should_send(first, 0.0)
    gate.sent(first, 0.0)
    assert not gate.should_send(first, 1.0)
    assert not gate.should_send(DriveCommand(0.31, 0.14), 1.0)
    assert gate.should_send(DriveCommand(0.33, 0.1), 1.0)
    assert gate.should_send(DriveCommand(0.3, 0.16), 1.0)


def test_gate_always_sends_an_exact_stop_once():
    gate = CommandGate(linear_deadband=0.1, angular_deadband=0.1)
    gate.sent(DriveCommand(0.01, 0.01), 0.0)
    assert gate.should_send(STOP, 0.1)
    gate.sent(STOP, 0.1)
    assert not gate.should_send(STOP, 0.2)


def test_gate_resends_an_unchanged_command_after_the_interval():
    gate = CommandGate(resend_interval=0.5)
    gate.sent(STOP, 10.0)
    assert not gate.should_send(STOP, 10.4)
    assert gate.should_send(STOP, 10.5)


def test_gate_retries_after_a_failure_only_after_the_delay():
    gate = CommandGate(retry_delay=0.5)
    command = DriveCommand(0.2, 0.0)
    assert gate.should_send(command, 1.0)
    gate.failed(1.0)
    assert not gate.should_send(command, 1.2)
    assert gate.should_send(command, 1.5)
    gate.sent(command, 1.5)
    assert not gate.should_send(command, 1.6)


def test_gate_retries_a_failed_command_even_inside_the_deadband():
    gate = CommandGate(retry_delay=0.5)
    command = DriveCommand(0.2, 0.0)
    gate.sent(command, 0.0)
    gate.failed(1.0)
    assert gate.should_send(command, 1.5)


def test_gate_starts_afresh_when_the_clock_goes_back():
    gate = CommandGate(retry_delay=0.5)
    gate.sent(STOP, 100.0)
    gate.failed(100.0)
    assert gate.should_send(STOP, 0.1)


def test_gate_with_every_frame_sends_each_command_even_unchanged():
    gate = CommandGate(linear_deadband=0.1, angular_deadband=0.1, every_frame=True)
    for now in (0.0, 0.033, 0.066):
        assert gate.should_send(STOP, now)
        gate.sent(STOP, now)


def test_gate_with_every_frame_still_waits_out_the_retry_delay():
    gate = CommandGate(retry_delay=0.5, every_frame=True)
    gate.failed(1.0)
    assert not gate.should_send(STOP, 1.2)
    assert gate.should_send(STOP, 1.5)
