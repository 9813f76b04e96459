"""Bad world and robot files: each is refused with a ModelFileError that names
the file and line, or loads with a Skipped record that names what was left
out, and the Simulation still builds from what loaded."""
import subprocess
import sys
from pathlib import Path

import pytest

from flatsim.errors import FlatsimError, ModelFileError
from flatsim.loading.sdf_world import find_balls, load_world, parse_world, white_balls
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world.drive import make_drive
from flatsim.world.sim import Simulation

CHASE_HOUSE = Path(__file__).resolve().parents[2] / 'my_robot' / 'worlds' / 'chase_house.world'
MY_ROBOT_URDF = expand_xacro(str(Path(__file__).resolve().parents[2] / 'my_robot' / 'urdf'
                                 / 'my_robot.xacro'))


def sdf_world(body):
    return '<?xml version="1.0"?>\n<sdf version="1.6">\n<world name="bad">\n%s\n</world>\n</sdf>\n' % body


def model(name, geometry, static=True, link='link', pose='0 0 0 0 0 0'):
    return ('<model name="%s"><static>%d</static><pose>%s</pose><link name="%s">'
            '<collision name="collision"><geometry>%s</geometry></collision>'
            '<visual name="visual"><geometry>%s</geometry></visual></link></model>'
            % (name, static, pose, link, geometry, geometry))


BALL = model('white_ball', '<sphere><radius>0.1</radius></sphere>', static=False, pose='1 0 0.1 0 0 0')
WALL = model('wall', '<box><size>2 0.2 1</size></box>', pose='0 2 0.5 0 0 0')


def reasons(spec):
    return {str(skipped) for skipped in spec.skipped}


def only_reason(spec, subject):
    found = [str(s) for s in spec.skipped if s.subject == subject]
    assert len(found) == 1, reasons(spec)
    return found[0]


# World files --------------------------------------------------------------------

@pytest.mark.parametrize('keep_fraction', [0.0, 0.1, 0.5, 0.99])
def test_truncated_world_is_refused_with_file_and_line(tmp_path, keep_fraction):
    data = CHASE_HOUSE.read_bytes()
    path = tmp_path / 'truncated.world'
    path.write_bytes(data[:int(len(data) * keep_fraction)])
    with pytest.raises(ModelFileError) as caught:
        load_world(path)
    message = str(caught.value)
    assert message.startswith(str(path))
    assert 'not well-formed XML' in message
    if keep_fraction:
        assert caught.value.line == data[:int(len(data) * keep_fraction)].count(b'\n') + 1


def test_world_that_does_not_exist_is_refused(tmp_path):
    missing = tmp_path / 'nowhere.world'
    with pytest.raises(ModelFileError, match='cannot read world file: No such file'):
        load_world(missing)


def test_world_without_a_ball_loads_and_builds_with_nothing_to_chase():
    spec = parse_world(sdf_world(WALL))
    assert [m.name for m in spec.models] == ['wall']
    assert find_balls(spec) == [] and white_balls(spec) == []
    sim = Simulation(spec)
    assert [m.kind for m in sim.models.values()] == ['static']


@pytest.mark.parametrize('geometry, subject, reason', [
    ('<box><size>-1 1 1</size></box>', 'box/link/collision', "box size '-1 1 1' is not positive"),
    ('<box><size>1 0 1</size></box>', 'box/link/collision', "box size '1 0 1' is not positive"),
    ('<sphere><radius>0</radius></sphere>', 'box/link/collision', "sphere radius '0' is not positive"),
    ('<sphere><radius>-0.1</radius></sphere>', 'box/link/collision', "sphere radius '-0.1' is not positive"),
    ('<cylinder><radius>0.5</radius><length>0</length></cylinder>', 'box/link/collision',
     "cylinder length '0' is not positive"),
    ('<cylinder><radius>-0.5</radius><length>1</length></cylinder>', 'box/link/collision',
     "cylinder radius '-0.5' is not positive"),
    ('<plane><normal>0 0 1</normal><size>0 10</size></plane>', 'box/link/collision',
     "plane size '0 10' is not positive"),
    ('<plane><normal>0 0 0</normal><size>10 10</size></plane>', 'box/link/collision',
     "plane normal '0 0 0' has no direction"),
    ('<box><size>nan 1 1</size></box>', 'box/link/collision', "box size 'nan 1 1' is not finite"),
    ('<box><size>1e999 1 1</size></box>', 'box/link/collision', "box size '1e999 1 1' is not finite"),
    ('<sphere><radius>1e-300</radius></sphere>', 'box/link/collision',
     "sphere radius '1e-300' is outside the 0.0001 to 1e+06 m that flatsim simulates"),
    ('<box><size>1 1e300 1</size></box>', 'box/link/collision',
     "box size '1 1e300 1' is outside the 0.0001 to 1e+06 m that flatsim simulates"),
    ('<torus><radius>1</radius></torus>', 'box/link/collision',
     'no box, cylinder, sphere or plane in <geometry>'),
    ('', 'box/link/collision', 'no box, cylinder, sphere or plane in <geometry>'),
])
def test_bad_sizes_and_unknown_geometry_leave_the_shape_out(geometry, subject, reason):
    spec = parse_world(sdf_world(model('box', geometry) + BALL))
    assert only_reason(spec, subject) == '%s: %s; left out' % (subject, reason)
    assert only_reason(spec, 'box/link/visual') == 'box/link/visual: %s; left out' % reason
    box = spec.model('box')
    assert box.collisions == [] and box.visuals == []
    sim = Simulation(spec)
    assert sim.models['box'].prim_ids == []
    assert sim.models['white_ball'].kind == 'ball'


def test_state_naming_models_and_links_that_do_not_exist_is_reported_and_ignored():
    state = ('<state world_name="bad"><model name="ghost"><pose>5 5 0 0 0 0</pose></model>'
             '<model name="wall"><pose>0 3 0.5 0 0 0</pose><link name="no_such_link">'
             '<pose>9 9 9 0 0 0</pose></link></model></state>')
    spec = parse_world(sdf_world(WALL + BALL + state))
    assert only_reason(spec, 'state of model ghost') == \
        'state of model ghost: no such model in the world; its saved pose is ignored'
    assert only_reason(spec, 'state of link wall/no_such_link') == \
        'state of link wall/no_such_link: no such link in the model; its saved pose is ignored'
    assert [m.name for m in spec.models] == ['wall', 'white_ball']
    assert (spec.model('wall').pose.x, spec.model('wall').pose.y) == (0.0, 3.0)
    sim = Simulation(spec)
    assert set(sim.models) == {'wall', 'white_ball'}


def test_ten_thousand_models_load_and_build():
    count = 10000
    models = ''.join(model('box_%d' % i, '<box><size>0.5 0.5 1</size></box>',
                           pose='%d %d 0.5 0 0 0' % (i % 100, i // 100)) for i in range(count))
    spec = parse_world(sdf_world(models + BALL))
    assert len(spec.models) == count + 1 and spec.skipped == []
    sim = Simulation(spec)
    assert len(sim.models) == count + 1
    # One collision and one visual primitive per box, and two for the ball.
    assert sum(len(m.prim_ids) for m in sim.models.values()) == 2 * count + 2
    sim.step()
    assert sim.model_pose('white_ball').x == pytest.approx(1.0)


# Robot descriptions --------------------------------------------------------------

def urdf(*parts):
    return '<?xml version="1.0"?>\n<robot name="bad_bot">\n%s\n</robot>\n' % '\n'.join(parts)


CHASSIS = ('<link name="chassis"><collision><geometry><box size="0.4 0.3 0.1"/></geometry></collision>'
           '<inertial><mass value="10"/></inertial></link>')
WHEELS = ''.join(
    '<link name="{0}_wheel"><collision><origin rpy="1.5707963 0 0"/><geometry>'
    '<cylinder radius="0.1" length="0.05"/></geometry></collision></link>'
    '<joint name="{0}_wheel_hinge" type="continuous"><parent link="chassis"/><child link="{0}_wheel"/>'
    '<origin xyz="0 {1} 0"/><axis xyz="0 1 0"/></joint>'.format(side, y)
    for side, y in (('left', 0.15), ('right', -0.15)))


def spawn(spec):
    sim = Simulation()
    robot = sim.spawn_robot('bad_bot', spec, Pose())
    for _ in range(10):
        sim.step()
    return sim, robot


def test_joint_naming_a_missing_link_is_refused_with_its_line():
    text = urdf(CHASSIS, WHEELS,
                '<joint name="camera_joint" type="fixed">\n<parent link="chassis"/><child link="camera"/>'
                '</joint>')
    joint_line = text[:text.index('camera_joint')].count('\n') + 1
    with pytest.raises(ModelFileError) as caught:
        load_robot(text, source='bad_bot.urdf')
    assert str(caught.value) == ("bad_bot.urdf:%d: joint camera_joint names child link 'camera', "
                                 "which the robot does not define" % joint_line)


def test_joint_naming_a_missing_parent_is_refused():
    text = urdf(CHASSIS, '<link name="wheel"/><joint name="hinge" type="continuous">'
                '<parent link="base"/><child link="wheel"/></joint>')
    with pytest.raises(ModelFileError, match="joint hinge names parent link 'base'"):
        load_robot(text)


@pytest.mark.parametrize('left, right, problem', [
    ('left_wheel_hinge', 'no_such_hinge', 'there is no joint no_such_hinge'),
    ('ghost_left', 'ghost_right', 'there is no joint ghost_left; there is no joint ghost_right'),
])
def test_drive_naming_missing_joints_is_reported_and_the_robot_stays(left, right, problem):
    plugin = ('<gazebo><plugin name="drive" filename="libgazebo_ros_diff_drive.so">'
              '<leftJoint>%s</leftJoint><rightJoint>%s</rightJoint></plugin></gazebo>' % (left, right))
    spec = load_robot(urdf(CHASSIS, WHEELS, plugin))
    assert spec.drive is None
    assert reasons(spec) == {'plugin drive (libgazebo_ros_diff_drive.so): %s: the robot stays where it is'
                             % problem}
    sim, robot = spawn(spec)
    assert robot.drive is None
    assert sim.model_pose('bad_bot') == Pose(0.0, 0.0, robot.z)


def test_sensor_on_a_missing_link_is_reported_and_left_out():
    sensor = ('<gazebo reference="camera_link"><sensor type="camera" name="camera1"><camera/>'
              '<plugin name="camera_controller" filename="libgazebo_ros_camera.so"/></sensor></gazebo>')
    spec = load_robot(urdf(CHASSIS, WHEELS, sensor))
    assert spec.cameras == []
    assert reasons(spec) == {'<gazebo reference="camera_link">: the robot has no link named camera_link, '
                             'so its tags are ignored'}
    _, robot = spawn(spec)
    assert robot.sensors == []


def test_sensor_on_a_joint_name_says_sensors_need_a_link():
    sensor = ('<gazebo reference="left_wheel_hinge"><sensor type="ray" name="laser"><ray/>'
              '<plugin name="laser" filename="libgazebo_ros_laser.so"/></sensor></gazebo>')
    spec = load_robot(urdf(CHASSIS, WHEELS, sensor))
    assert spec.lasers == []
    assert reasons(spec) == {'<gazebo reference="left_wheel_hinge">: the robot has no link named '
                             'left_wheel_hinge, so its tags are ignored (sensors need a link)'}


@pytest.mark.parametrize('text, message', [
    ('', 'the robot description is empty'),
    ('<robot name="r">', 'malformed XML: no element found'),
    ('<sdf/>', 'expected a <robot> URDF, found <sdf>'),
    ('<robot name="r"/>', "robot 'r' has no <link>"),
])
def test_robot_descriptions_that_are_not_robots_are_refused(text, message):
    with pytest.raises(ModelFileError, match=message):
        load_robot(text, source='robot_description')


def test_a_refused_robot_leaves_the_simulation_as_it_was():
    sim = Simulation(parse_world(sdf_world(WALL + BALL)))
    with pytest.raises(FlatsimError, match='a model named .white_ball. already exists'):
        sim.spawn_robot('white_ball', load_robot(urdf(CHASSIS, WHEELS)), Pose())
    assert set(sim.models) == {'wall', 'white_ball'}
    sim.step()


def test_a_ball_too_small_to_simulate_is_left_out_and_the_world_steps():
    spec = parse_world(sdf_world(model('dust', '<sphere><radius>1e-300</radius></sphere>', static=False)
                                 + BALL))
    sim = Simulation(spec)
    sim.step()
    assert sim.models['dust'].kind == 'static' and sim.models['white_ball'].kind == 'ball'


@pytest.mark.parametrize('step, kept', [('1e300', 0.05), ('1e-300', 1e-05), ('0.001', 0.001)])
def test_a_world_step_flatsim_cannot_take_is_named_and_its_own_step_said(step, kept):
    spec = parse_world(sdf_world('<physics type="ode"><max_step_size>%s</max_step_size></physics>'
                                 % step + BALL))
    assert spec.max_step_size == kept
    if step != '0.001':
        reason = only_reason(spec, 'physics max_step_size')
        # The launch's ~step_size is what steps the world, whatever the world file says.
        assert 'using' not in reason
        assert reason.endswith('flatsim steps by its own ~step_size parameter (the step_size of '
                               'empty_world.launch and world.launch), not by the world\'s')


def test_models_nested_two_thousand_deep_load_with_the_deep_ones_left_out():
    inner = '<link name="l"><collision name="c"><geometry><box><size>1 1 1</size></box></geometry>' \
            '</collision></link>'
    for depth in range(2000):
        inner = '<model name="m%d">%s%s</model>' % (depth, '<static>1</static>' if depth == 1999 else '',
                                                   inner)
    spec = parse_world(sdf_world(inner))
    assert 'models nested deeper than 100 levels are left out' in only_reason(
        spec, 'm1999/.../m1898')
    Simulation(spec).step()


# Loads a world of models nested 2000 deep while another simulation waits to be collected,
# and collects it when the calls are margin levels from Python's recursion limit, as a
# collection that comes at that moment would. pymunk frees a body through Python callbacks
# that first take its shapes and joints out of their space; at the limit they cannot run,
# the body is freed with its shapes still in the space, and the process crashes.
DEEP_WORLD_WHILE_COLLECTING = """
import gc, sys
from flatsim.loading.sdf_world import parse_world
from flatsim.world.sim import Simulation
box = '<link name="l"><collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link>'
def world(depth):
    text = box
    for level in range(depth):
        text = '<model name="m%d">%s</model>' % (level, text)
    return '<sdf version="1.6"><world name="w">%s</world></sdf>' % text
margin = int(sys.argv[1])
gc.disable()
left = Simulation(parse_world(world(3), model_paths=[]))
for _ in range(5):
    left.step()
left.itself = left
del left
armed = [True]
def collect_near_the_limit(frame, event, arg):
    if event != 'call' or not armed[0]:
        return
    depth = 0
    while frame is not None:
        depth, frame = depth + 1, frame.f_back
    if depth >= sys.getrecursionlimit() - margin:
        armed[0] = False
        gc.collect()
sys.setprofile(collect_near_the_limit)
Simulation(parse_world(world(2000), model_paths=[])).step()
sys.setprofile(None)
print('loaded')
"""


@pytest.mark.parametrize('margin', [3, 5, 8, 12])
def test_a_world_nested_thousands_deep_is_loaded_without_nearing_pythons_recursion_limit(margin):
    done = subprocess.run([sys.executable, '-c', DEEP_WORLD_WHILE_COLLECTING, str(margin)],
                          capture_output=True, text=True, timeout=120)
    assert (done.returncode, done.stdout.strip()) == (0, 'loaded'), done.stderr[-2000:]


@pytest.mark.parametrize('rate', ['1e9', '1e300'])
def test_a_sensor_faster_than_any_step_updates_every_step(rate):
    robot = load_robot(MY_ROBOT_URDF.replace('<update_rate>30</update_rate>',
                                             '<update_rate>%s</update_rate>' % rate, 1))
    clamped, = [item for item in robot.skipped if 'beyond any physics rate' in str(item)]
    # The sensor stays: its record says it was adjusted, not skipped.
    assert clamped.verb == 'adjusted' and 'the sensor is kept' in clamped.reason
    sim = Simulation()
    sim.spawn_robot('my_robot', robot, Pose())
    camera = next(slot for slot in sim.robots()[0].sensors if slot.kind == 'camera')
    updates = 0
    for _ in range(5):
        sim.step()
        updates += camera in sim.due_sensors()
    assert updates == 5


def test_a_thousand_link_chain_loads_and_spawns():
    links = ''.join('<link name="l%d"><collision><origin xyz="0.05 0 0.1"/><geometry>'
                    '<box size="0.1 0.1 0.1"/></geometry></collision></link>' % i for i in range(1000))
    joints = ''.join('<joint name="j%d" type="fixed"><parent link="l%d"/><child link="l%d"/>'
                     '<origin xyz="0.1 0 0"/></joint>' % (i, i - 1, i) for i in range(1, 1000))
    robot = load_robot('<robot name="chain">%s%s</robot>' % (links, joints))
    sim = Simulation()
    sim.spawn_robot('chain', robot, Pose())
    assert max(x for x, _ in robot.footprint) == pytest.approx(100.0)


def test_a_drive_too_slow_to_ever_update_is_clamped_with_a_warning():
    plugin = ('<gazebo><plugin name="drive" filename="libgazebo_ros_diff_drive.so">'
              '<leftJoint>left_wheel_hinge</leftJoint><rightJoint>right_wheel_hinge</rightJoint>'
              '<updateRate>1e-300</updateRate></plugin></gazebo>')
    spec = load_robot(urdf(CHASSIS, WHEELS, plugin))
    assert spec.drive.update_rate == 1e-3
    clamped, = [item for item in spec.skipped if 'would never update the drive' in item.reason]
    assert clamped.verb == 'adjusted'
    sim, robot = spawn(spec)
    robot.drive.set_command(0.5, 0.0)
    sim.step()
    spec.drive.update_rate = 1e-300      # past the reader: the drive itself refuses it
    with pytest.raises(FlatsimError, match='would never update the drive'):
        make_drive(spec.drive)
