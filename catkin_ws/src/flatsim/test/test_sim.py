"""flatsim.world.sim.Simulation without ROS: colliders, the ball, sensor schedules, model state."""
import math
import pathlib

import pymunk
import pytest

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world, parse_world
from flatsim.pose import Pose
from flatsim.world.sim import Simulation

SRC = pathlib.Path(__file__).resolve().parents[2]
CHASE_HOUSE = SRC / 'my_robot' / 'worlds' / 'chase_house.world'

TABLE_HALF = 0.5
LEG_RADIUS = 0.03


def _leg(name, x, y):
    return '''
      <link name="{name}">
        <pose>{x} {y} 0 0 0 0</pose>
        <collision name="{name}_collision">
          <pose>0 0 0.34 0 0 0</pose>
          <geometry><cylinder><radius>{r}</radius><length>0.68</length></cylinder></geometry>
        </collision>
      </link>'''.format(name=name, x=x, y=y, r=LEG_RADIUS)


def _ball_model(name, x, y, radius=0.1):
    return '''
    <model name="{name}">
      <pose>{x} {y} {radius} 0 0 0</pose>
      <link name="link">
        <inertial><mass>0.5</mass></inertial>
        <collision name="collision">
          <geometry><sphere><radius>{radius}</radius></sphere></geometry>
        </collision>
        <visual name="visual">
          <geometry><sphere><radius>{radius}</radius></sphere></geometry>
        </visual>
      </link>
    </model>'''.format(name=name, x=x, y=y, radius=radius)


def table_world(state=''):
    """A table (top at 0.7 m on four legs) centred at the origin, a wall at x = 4, a ball at (2, 2)."""
    corner = TABLE_HALF - LEG_RADIUS
    legs = ''.join(_leg('leg_%d' % i, sx * corner, sy * corner)
                   for i, (sx, sy) in enumerate([(1, 1), (1, -1), (-1, 1), (-1, -1)]))
    return '''<?xml version="1.0"?>
<sdf version="1.6">
  <world name="default">
    <model name="table">
      <static>1</static>
      <pose>0 0 0 0 0 0</pose>
      <link name="top">
        <collision name="top_collision">
          <pose>0 0 0.7 0 0 0</pose>
          <geometry><box><size>{size} {size} 0.04</size></box></geometry>
        </collision>
      </link>{legs}
    </model>
    <model name="wall">
      <static>1</static>
      <pose>4 0 0 0 0 0</pose>
      <link name="link">
        <collision name="collision">
          <pose>0 0 0.5 0 0 0</pose>
          <geometry><box><size>0.2 6 1</size></box></geometry>
        </collision>
      </link>
    </model>{ball}{state}
  </world>
</sdf>'''.format(size=2 * TABLE_HALF, legs=legs, ball=_ball_model('ball', 2.0, 2.0), state=state)


def collider_at(sim, x, y):
    """The static collider shape covering the floor point (x, y), or None."""
    hit = sim.physics.space.point_query_nearest((x, y), 0.0, pymunk.ShapeFilter())
    if hit is None or hit.shape.body is not sim.physics.space.static_body:
        return None
    return hit.shape


def run(sim, seconds):
    for _ in range(int(round(seconds / sim.step_size))):
        sim.step()


def test_only_geometry_at_working_height_becomes_a_collider():
    sim = Simulation(parse_world(table_world()))
    # Four legs and the wall; the table top floats above the robot.
    assert sim.physics.static_count() == 5
    assert collider_at(sim, 0.0, 0.0) is None
    corner = TABLE_HALF - LEG_RADIUS
    assert collider_at(sim, corner, corner) is not None
    assert collider_at(sim, -corner, -corner) is not None
    assert collider_at(sim, 4.0, 2.9) is not None
    assert collider_at(sim, 4.2, 0.0) is None


def test_a_ball_rolls_under_a_table_top_but_stops_at_a_wall():
    sim = Simulation(parse_world(table_world()))
    sim.set_model_state('ball', Pose(0.0, -1.5, 0.1), twist=(0.0, 3.0, 0.0))
    run(sim, 1.0)
    assert sim.model_pose('ball').y > 0.6
    sim.set_model_state('ball', Pose(2.0, 0.0, 0.1), twist=(3.0, 0.0, 0.0))
    run(sim, 2.0)
    # The wall's near face is at x = 3.9; the ball's centre stays a radius short of it.
    assert sim.model_pose('ball').x < 3.9 - 0.1 + 0.01


def test_the_ball_is_dynamic_and_the_robot_pushes_it(my_robot_spec):
    sim = Simulation(parse_world(table_world()))
    assert sim.models['ball'].kind == 'ball'
    assert sim.models['table'].kind == 'static'
    sim.set_model_state('ball', Pose(1.0, -2.0, 0.1))
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(0.0, -2.0, 0.0))
    robot.drive.set_command(0.5, 0.0)
    run(sim, 3.0)
    robot_x = sim.model_pose('my_robot').x
    ball = sim.model_pose('ball')
    assert robot_x > 0.5
    assert ball.x > 1.0 + 0.3
    # The ball stays ahead of the robot's front (its hull reaches x = 0.23 + camera).
    assert ball.x > robot_x + 0.23
    assert abs(ball.y + 2.0) < 0.3


def test_sensors_fall_due_at_their_rates_in_sim_time(my_robot_spec):
    sim = Simulation(parse_world(table_world()))
    sim.spawn_robot('my_robot', my_robot_spec, Pose(-2.0, 0.0, 0.0))
    due_times = {'camera': [], 'laser': []}
    # Updates scheduled in the first second of sim time, [0, 1).
    while True:
        sim.step()
        if sim.time >= 1.0 - 1e-9:
            break
        for slot in sim.due_sensors():
            due_times[slot.kind].append(sim.time)
    assert len(due_times['camera']) == 30
    assert len(due_times['laser']) == 40
    for kind, rate in [('camera', 30.0), ('laser', 40.0)]:
        for k, when in enumerate(due_times[kind]):
            assert k / rate - 1e-9 <= when < k / rate + sim.step_size + 1e-9


def test_sensors_keep_their_schedule_when_nobody_asks_for_a_while(my_robot_spec):
    sim = Simulation(parse_world(table_world()))
    sim.spawn_robot('my_robot', my_robot_spec, Pose(-2.0, 0.0, 0.0))
    run(sim, 0.5)
    kinds = sorted(slot.kind for slot in sim.due_sensors())
    assert kinds == ['camera', 'laser']
    # Missed updates are not made up in a burst.
    sim.step()
    assert sim.due_sensors() == []


def test_set_model_state_of_an_unknown_model_names_it():
    sim = Simulation(parse_world(table_world()))
    with pytest.raises(FlatsimError, match='no_such_thing'):
        sim.set_model_state('no_such_thing', Pose(1.0, 1.0, 0.0))
    with pytest.raises(FlatsimError, match='no_such_thing'):
        sim.model_pose('no_such_thing')


def test_a_static_model_is_moved_with_its_colliders_and_reset_back():
    sim = Simulation(parse_world(table_world()))
    corner = TABLE_HALF - LEG_RADIUS
    sim.set_model_state('table', Pose(-2.0, 1.0, 0.0, yaw=math.pi / 2))
    assert sim.model_pose('table') == Pose(-2.0, 1.0, 0.0, yaw=math.pi / 2)
    assert collider_at(sim, corner, corner) is None
    assert collider_at(sim, -2.0 + corner, 1.0 + corner) is not None
    assert sim.physics.static_count() == 5
    sim.reset_world()
    assert sim.model_pose('table') == Pose()
    assert collider_at(sim, corner, corner) is not None
    assert collider_at(sim, -2.0 + corner, 1.0 + corner) is None


def test_reset_world_puts_moving_models_back_at_rest(my_robot_spec):
    sim = Simulation(parse_world(table_world()))
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(-2.0, -2.0, 0.0, yaw=0.5))
    sim.set_model_state('ball', Pose(1.0, 2.5, 0.1), twist=(0.5, 0.0, 0.0))
    robot.drive.set_command(0.4, 0.3)
    run(sim, 1.0)
    assert sim.model_pose('ball').x > 1.2
    assert math.hypot(sim.model_pose('my_robot').x + 2.0, sim.model_pose('my_robot').y + 2.0) > 0.1
    time_before = sim.time
    sim.reset_world()
    ball, pose = sim.model_pose('ball'), sim.model_pose('my_robot')
    assert (ball.x, ball.y) == pytest.approx((2.0, 2.0), abs=1e-9)
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((-2.0, -2.0, 0.5), abs=1e-9)
    assert sim.model_twist('ball') == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert sim.time == time_before
    # The drive's command is forgotten too: the robot stays where it was put.
    run(sim, 0.5)
    pose = sim.model_pose('my_robot')
    assert (pose.x, pose.y) == pytest.approx((-2.0, -2.0), abs=1e-3)


def test_state_block_poses_win_over_model_poses():
    state = '''
    <state world_name="default">
      <model name="ball">
        <pose>-1.5 3 0.1 0 0 0</pose>
        <link name="link"><pose>-1.5 3 0.1 0 0 0</pose></link>
      </model>
    </state>'''
    plain = Simulation(parse_world(table_world()))
    assert (plain.model_pose('ball').x, plain.model_pose('ball').y) == pytest.approx((2.0, 2.0))
    sim = Simulation(parse_world(table_world(state)))
    ball = sim.model_pose('ball')
    assert (ball.x, ball.y) == pytest.approx((-1.5, 3.0), abs=1e-9)


def test_sensors_see_the_ball_where_the_state_block_puts_it(my_robot_spec):
    state = '''
    <state world_name="default">
      <model name="ball">
        <pose>-1.5 3 0.1 0 0 0</pose>
      </model>
    </state>'''
    sim = Simulation(parse_world(table_world(state)))
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(-1.5, 1.0, 0.0, yaw=math.pi / 2))
    laser = next(slot for slot in robot.sensors if slot.kind == 'laser')
    hokuyo_y = sim.sensor_pose(laser).y
    ranges = sim.sense(laser)
    middle = (ranges[len(ranges) // 2 - 1] + ranges[len(ranges) // 2]) / 2
    stddev = laser.config.noise_stddev
    assert middle == pytest.approx(3.0 - 0.1 - hokuyo_y, abs=3 * stddev)



def test_the_camera_renders_where_a_cylinder_is_in_view_but_missed_by_some_columns(my_robot_spec):
    # chase_house.world's pillar (r = 0.2 m at (1.3, 2.4)) seen from the side.
    sim = Simulation(load_world(CHASE_HOUSE))
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(0.885, 0.478, 0.0, yaw=1.022))
    camera = next(slot for slot in robot.sensors if slot.kind == 'camera')
    for heading in range(-10, 11):
        sim.set_model_state('my_robot', Pose(0.885, 0.478, 0.0, yaw=1.022 + math.radians(heading)))
        image = sim.sense(camera)
        assert image.shape == (800, 800, 3)


def _push_ball_into_wall(sim, robot):
    """Push the ball toward the wall at x = 4, weaving; every pose and scan on the way."""
    sim.set_model_state('my_robot', Pose(1.0, 2.1, 0.0, yaw=0.05))
    sim.set_model_state('ball', Pose(1.6, 2.0, 0.1))
    lidar = next(slot for slot in robot.sensors if slot.kind == 'laser')
    trace = []
    for step in range(2000):
        if step % 250 == 0:
            robot.drive.set_command(0.8, (-0.15, 0.15)[step // 250 % 2])
        sim.step()
        trace.append(tuple(sim.physics.pose(sim.models[name].handle) for name in ('my_robot', 'ball')))
        if lidar in sim.due_sensors():
            trace.append(tuple(sim.sense(lidar)))
    return trace


def test_after_reset_simulation_the_same_placements_give_the_same_run_bit_for_bit(my_robot_spec):
    fresh = Simulation(parse_world(table_world()), seed=3)
    robot = fresh.spawn_robot('my_robot', my_robot_spec, Pose(-2.0, -2.0, 0.0))
    expected = _push_ball_into_wall(fresh, robot)
    assert fresh.model_pose('ball').x > 2.6  # pushed: the space has cached contacts
    used = Simulation(parse_world(table_world()), seed=3)
    robot = used.spawn_robot('my_robot', my_robot_spec, Pose(-2.0, -2.0, 0.0))
    # Another history first: the ball thrown about, the robot scraping along the table legs,
    # the lidar drawing noise.
    used.set_model_state('ball', Pose(3.5, 0.0, 0.1), twist=(2.0, 1.5, 0.0))
    robot.drive.set_command(0.7, 0.9)
    for _ in range(3000):
        used.step()
        for slot in used.due_sensors():
            used.sense(slot)
    used.reset_time()
    assert used.time == 0.0
    assert _push_ball_into_wall(used, robot) == expected


def test_diverged_physics_starts_over_and_stops_when_that_keeps_happening():
    sim = Simulation(parse_world(table_world()))
    for round_ in range(3):
        sim.models['ball'].handle.body.velocity = (math.nan, 0.0)
        with pytest.raises(FlatsimError, match='physics diverged'):
            sim.step()
        assert sim.recover().stopped == (round_ == 2)
        assert sim.model_pose('ball').x == pytest.approx(2.0)
    assert sim.paused
    sim.paused = False
    sim.step()
    assert sim.divergences == []
