"""The turtles on their canvas, without ROS: spawn names and errors, kill,
reset and clear, pens and the colour sensor, rotation goals, and draw_square's
steering driving a square on the canvas."""
import math

import numpy as np
import pytest

from turtlesim.canvas import DEFAULT_BACKGROUND, Canvas, Pen, to_pixel
from turtlesim.motion import CANVAS_METERS, CENTRE, PI, UPDATE_PERIOD, TurtlesimError
from turtlesim.square import SquareDriver
from turtlesim.world import TurtleWorld

RED = (255, 0, 0)


def world_with_turtle1():
    world = TurtleWorld()
    assert world.spawn('', CENTRE, CENTRE, 0.0) == 'turtle1'
    return world


def pixel(world, x, y):
    """The canvas pixel at pose coordinates (y up from the bottom)."""
    column, row = to_pixel((x, CANVAS_METERS - y))
    return tuple(int(c) for c in world.canvas.pixels[row, column])


def run(world, seconds, start=0.0):
    updates = []
    for tick in range(int(round(seconds / UPDATE_PERIOD))):
        updates = world.tick(start + tick * UPDATE_PERIOD)
    return {u.name: u for u in updates}


def test_spawn_names_turtles_after_the_last_number_and_skips_taken_names():
    world = world_with_turtle1()
    world.spawn('turtle3', 1.0, 1.0, 0.0)
    assert [world.spawn('', 2.0, 2.0, 0.0) for _ in range(3)] == ['turtle2', 'turtle4', 'turtle5']
    assert world.spawn('leonardo', 3.0, 3.0, 0.0) == 'leonardo'


@pytest.mark.parametrize('name, message', [
    ('turtle1', r'A turtled named \[turtle1\] already exists'),
    ('bad name!', 'not a legal ROS name'),
    ('1turtle', 'not a legal ROS name'),
])
def test_spawn_refuses_a_taken_or_illegal_name(name, message):
    world = world_with_turtle1()
    with pytest.raises(TurtlesimError, match=message):
        world.spawn(name, 1.0, 1.0, 0.0)
    assert list(world.turtles) == ['turtle1']


def test_spawn_refuses_nan_and_places_a_turtle_off_the_canvas_at_the_wall():
    world = world_with_turtle1()
    with pytest.raises(TurtlesimError, match='finite'):
        world.spawn('', float('nan'), 1.0, 0.0)
    world.spawn('far', 20.0, -3.0, 0.0)
    update = run(world, UPDATE_PERIOD)['far']
    assert update.pose[:2] == pytest.approx((CANVAS_METERS, 0.0))
    assert update.clamped_from == pytest.approx((20.0, CANVAS_METERS + 3.0))


def test_kill_removes_a_turtle_and_refuses_an_unknown_name():
    world = world_with_turtle1()
    world.spawn('leonardo', 1.0, 1.0, 0.0)
    world.kill('leonardo')
    assert list(world.turtles) == ['turtle1']
    with pytest.raises(TurtlesimError, match=r'Tried to kill turtle \[leonardo\], which does not exist'):
        world.kill('leonardo')
    for request in (lambda: world.set_pen('leonardo', 1, 2, 3, 4, 0),
                    lambda: world.teleport_absolute('leonardo', 1.0, 1.0, 0.0),
                    lambda: world.command('leonardo', 1.0, 0.0, 0.0, 0.0)):
        with pytest.raises(TurtlesimError, match=r'no turtle named \[leonardo\]'):
            request()


def test_reset_leaves_a_new_turtle1_in_the_centre_on_a_clean_canvas():
    world = world_with_turtle1()
    world.spawn('', 1.0, 1.0, 0.0)
    world.command('turtle1', 1.0, 0.0, 0.0, now=0.0)
    run(world, 0.5)
    assert world.reset((10, 20, 30)) == 'turtle1'
    assert list(world.turtles) == ['turtle1']
    assert world.turtles['turtle1'].motion.pose() == pytest.approx((CENTRE, CENTRE, 0.0, 0.0, 0.0))
    assert np.all(world.canvas.pixels == (10, 20, 30))
    assert world.spawn('', 1.0, 1.0, 0.0) == 'turtle2'


def test_the_default_pen_draws_the_path_and_the_sensor_reads_it_back():
    world = world_with_turtle1()
    start = run(world, UPDATE_PERIOD)['turtle1']
    assert start.color == DEFAULT_BACKGROUND
    world.command('turtle1', 1.0, 0.0, 0.0, now=1.0)
    update = run(world, 0.5, start=1.0)['turtle1']
    assert update.color == Pen().rgb
    x_end = update.pose[0]
    assert x_end == pytest.approx(CENTRE + (round(0.5 / UPDATE_PERIOD)) * UPDATE_PERIOD)
    for x in np.linspace(CENTRE + 0.05, x_end - 0.05, 10):
        assert pixel(world, x, CENTRE) == Pen().rgb
        # Width 3: one pixel either side of the centre line, background beyond.
        assert pixel(world, x, CENTRE + 1.0 / 45) == Pen().rgb
        assert pixel(world, x, CENTRE + 2.5 / 45) == DEFAULT_BACKGROUND


def test_set_pen_colour_width_and_off():
    world = world_with_turtle1()
    world.set_pen('turtle1', 255, 0, 0, 9, 0)
    world.command('turtle1', 1.0, 0.0, 0.0, now=0.0)
    run(world, 0.5)
    assert pixel(world, CENTRE + 0.2, CENTRE + 4.0 / 45) == RED
    assert pixel(world, CENTRE + 0.2, CENTRE + 6.0 / 45) == DEFAULT_BACKGROUND
    world.set_pen('turtle1', 0, 255, 0, 3, 1)
    assert world.turtles['turtle1'].pen.rgb == RED
    world.teleport_absolute('turtle1', 2.0, 2.0, math.pi / 2)
    world.command('turtle1', 1.0, 0.0, 0.0, now=1.0)
    run(world, 0.5, start=1.0)
    assert pixel(world, 2.0, 2.2) == DEFAULT_BACKGROUND


def test_pen_width_zero_draws_one_pixel_wide_as_qts_default_pen():
    world = world_with_turtle1()
    world.set_pen('turtle1', 0, 0, 0, 0, 0)
    assert world.turtles['turtle1'].pen.width == 1
    world.command('turtle1', 1.0, 0.0, 0.0, now=0.0)
    run(world, 0.5)
    column, row = to_pixel((CENTRE + 0.2, CANVAS_METERS - CENTRE))
    assert [tuple(world.canvas.pixels[r, column]) for r in (row - 1, row, row + 1)] == \
        [DEFAULT_BACKGROUND, (0, 0, 0), DEFAULT_BACKGROUND]


def test_teleports_draw_with_the_pen_on_and_run_in_order_at_the_next_update():
    world = world_with_turtle1()
    world.set_pen('turtle1', 255, 0, 0, 3, 0)
    world.teleport_absolute('turtle1', 2.0, 2.0, 0.0)
    world.teleport_relative('turtle1', 1.0, math.pi / 2)
    assert world.turtles['turtle1'].motion.pose()[:2] == pytest.approx((CENTRE, CENTRE))
    update = run(world, UPDATE_PERIOD)['turtle1']
    assert update.pose[:3] == pytest.approx((2.0, 3.0, math.pi / 2))
    assert pixel(world, 2.0, 2.5) == RED
    assert pixel(world, (CENTRE + 2.0) / 2, (CENTRE + 2.0) / 2) == RED


def test_clear_repaints_the_background_and_keeps_the_turtles():
    world = world_with_turtle1()
    world.command('turtle1', 1.0, 0.0, 0.0, now=0.0)
    run(world, 0.3)
    world.clear((1, 2, 3))
    assert np.all(world.canvas.pixels == (1, 2, 3))
    assert list(world.turtles) == ['turtle1']


def test_the_picture_shows_each_turtle_over_the_canvas_without_drawing_on_it():
    world = world_with_turtle1()
    picture = world.picture()
    column, row = to_pixel((CENTRE, CANVAS_METERS - CENTRE))
    assert tuple(picture[row, column]) != DEFAULT_BACKGROUND
    assert tuple(picture[10, 10]) == DEFAULT_BACKGROUND
    assert np.all(world.canvas.pixels == DEFAULT_BACKGROUND)


def test_canvas_colour_at_the_far_corner_stays_on_the_canvas():
    canvas = Canvas()
    assert canvas.color_at((CANVAS_METERS, CANVAS_METERS)) == DEFAULT_BACKGROUND


def rotation(world, theta, key='goal'):
    world.rotate_absolute('turtle1', key, theta)
    events = []
    for tick in range(400):
        world.tick(tick * UPDATE_PERIOD)
        events += world.take_rotation_events()
        if events and events[-1].kind != 'feedback':
            break
    return events


def test_rotate_absolute_turns_at_one_radian_per_second_to_within_the_tolerance():
    world = world_with_turtle1()
    events = rotation(world, -1.0)
    feedback = [e.value for e in events if e.kind == 'feedback']
    assert feedback[0] == pytest.approx(-1.0)
    assert all(b > a for a, b in zip(feedback, feedback[1:]))
    assert events[-1].kind == 'succeeded'
    theta = world.turtles['turtle1'].motion.theta
    assert abs(theta + 1.0) < 0.02
    assert events[-1].value == pytest.approx(-theta)
    assert len(feedback) == pytest.approx(1.0 / UPDATE_PERIOD, abs=2)


def test_rotate_absolute_takes_the_short_way_round():
    world = world_with_turtle1()
    world.teleport_absolute('turtle1', CENTRE, CENTRE, 3.0)
    world.tick(0.0)
    rotation(world, -3.0)
    assert world.turtles['turtle1'].motion.theta == pytest.approx(-3.0, abs=0.02)
    assert world.turtles['turtle1'].motion.angular == 0.0


def test_a_velocity_command_or_a_new_goal_aborts_a_rotation_and_cancel_stops_it():
    world = world_with_turtle1()
    world.rotate_absolute('turtle1', 'first', 2.0)
    world.tick(0.0)
    world.rotate_absolute('turtle1', 'second', 2.0)
    world.command('turtle1', 1.0, 0.0, 0.0, now=0.0)
    kinds = [(e.key, e.kind) for e in world.take_rotation_events() if e.kind != 'feedback']
    assert kinds == [('first', 'aborted'), ('second', 'aborted')]
    world.rotate_absolute('turtle1', 'third', 2.0)
    world.tick(0.0)
    world.cancel_rotation('turtle1', 'third')
    world.tick(0.0)
    assert world.take_rotation_events()[-1].kind == 'canceled'
    assert world.turtles['turtle1'].motion.angular == 0.0
    with pytest.raises(TurtlesimError):
        world.rotate_absolute('turtle1', 'nan', float('nan'))


def test_kill_and_reset_abort_a_running_rotation():
    world = world_with_turtle1()
    world.rotate_absolute('turtle1', 'goal', 2.0)
    world.kill('turtle1')
    assert [e.kind for e in world.take_rotation_events()] == ['aborted']
    world.spawn('turtle1', 1.0, 1.0, 0.0)
    world.rotate_absolute('turtle1', 'goal', 2.0)
    world.reset(DEFAULT_BACKGROUND)
    assert [e.kind for e in world.take_rotation_events()] == ['aborted']


def test_draw_square_steers_turtle1_round_a_square_on_the_canvas():
    world = TurtleWorld()
    world.reset(DEFAULT_BACKGROUND)
    driver = SquareDriver()
    log = []
    now = 0.0
    update = run(world, UPDATE_PERIOD)['turtle1']
    while log.count('Reached goal') < 8 and now < 40.0:
        command, lines = driver.update(update.pose)
        log += lines
        if command is not None:
            world.command('turtle1', command[0], 0.0, command[1], now)
        now += UPDATE_PERIOD
        update = world.tick(now)[0]
    assert log.count('Reached goal') == 8, 'a square takes about 24 s, not %.1f s' % now
    assert log[0] == 'New goal [%f %f, %f]' % (CENTRE + 2.0, CENTRE, 0.0)
    # Back near the start, facing +x again; draw_square's tolerances let it fall short a little.
    x, y, theta = update.pose[:3]
    assert (x, y) == pytest.approx((CENTRE, CENTRE), abs=0.3)
    assert abs(theta) < 0.1
    pen = Pen().rgb
    for side in ([(CENTRE + t, CENTRE) for t in (0.5, 1.0, 1.5)]
                 + [(CENTRE + 1.95, CENTRE + t) for t in (0.5, 1.0, 1.5)]
                 + [(CENTRE + t, CENTRE + 1.95) for t in (0.5, 1.0, 1.5)]
                 + [(CENTRE, CENTRE + t) for t in (0.5, 1.0, 1.5)]):
        assert pixel(world, *side) == pen, side
    assert pixel(world, CENTRE + 1.0, CENTRE + 1.0) == DEFAULT_BACKGROUND
    assert -PI <= theta < PI
