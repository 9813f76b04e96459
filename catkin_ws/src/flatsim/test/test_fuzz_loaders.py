"""Property tests: whatever the world and robot loaders are given, they either
load it or raise FlatsimError, and the Simulation builds from what they return.

Inputs are the project's own files mutated (bytes deleted or inserted, tags
swapped, numbers and attributes replaced) and XML trees generated from SDF and
URDF element names. The default profile keeps CI short; for a long run:

    HYPOTHESIS_PROFILE=long python -m pytest catkin_ws/src/flatsim/test/test_fuzz_loaders.py
"""
import contextlib
import functools
import os
import re
import signal
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, example, given, settings, strategies as st

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import parse_sdf_models, parse_world
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation

settings.register_profile('fuzz', max_examples=40, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile('long', max_examples=5000, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
FUZZ = settings.get_profile('long' if os.environ.get('HYPOTHESIS_PROFILE') == 'long' else 'fuzz')

# Wall-clock bound on one example: a loader that loops forever fails the test
# with the example that made it loop, instead of hanging the run.
EXAMPLE_TIME_LIMIT_S = 20

TEST_DIR = Path(__file__).resolve().parent
SRC = TEST_DIR.parents[1]
WORLD_FILES = [SRC / 'my_robot' / 'worlds' / 'chase_house.world'] + sorted(
    (TEST_DIR / 'fixtures' / 'worlds').glob('*.world'))
MY_ROBOT_XACRO = SRC / 'my_robot' / 'urdf' / 'my_robot.xacro'


class ExampleTooSlow(Exception):
    pass


@contextlib.contextmanager
def time_limit(seconds):
    def expire(_signum, _frame):
        raise ExampleTooSlow('example still running after %d s' % seconds)
    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@functools.lru_cache(maxsize=None)
def world_bytes(index):
    return WORLD_FILES[index].read_bytes()


@functools.lru_cache(maxsize=None)
def my_robot_urdf():
    return expand_xacro(MY_ROBOT_XACRO).encode('utf-8')


# The contract under test ----------------------------------------------------------

def load_world_into_simulation(data):
    """Load SDF bytes as a world and build a Simulation from it; FlatsimError from either
    step is an answer too (the node reports both the same way, and exits)."""
    with time_limit(EXAMPLE_TIME_LIMIT_S):
        try:
            world = parse_world(data, 'fuzzed.world')
            sim = Simulation(world)
        except FlatsimError as error:
            assert str(error)
            event('refused: %s' % type(error).__name__)
            return None
        event('loaded')
        for _ in range(3):
            sim.step()
        return sim


def load_robot_into_simulation(data):
    """Load URDF bytes and spawn the robot; FlatsimError from either step is an answer too."""
    with time_limit(EXAMPLE_TIME_LIMIT_S):
        try:
            spec = load_robot(data, source='fuzzed.urdf')
            sim = Simulation()
            sim.spawn_robot('fuzzed', spec, Pose())
        except FlatsimError as error:
            assert str(error)
            event('refused: %s' % type(error).__name__)
            return None
        event('loaded')
        for _ in range(3):
            sim.step()
        return sim


def load_sdf_models(data):
    with time_limit(EXAMPLE_TIME_LIMIT_S):
        try:
            models, _ = parse_sdf_models(data, 'fuzzed.sdf')
        except FlatsimError as error:
            assert str(error)
            event('refused: %s' % type(error).__name__)
            return None
        event('loaded')
        sim = Simulation()
        for model in models:
            sim.add_world_model(model)
        return sim


# Mutations of real files ----------------------------------------------------------

TAG = re.compile(rb'<(/?)([A-Za-z_][\w.:-]*)')
NUMBER = re.compile(rb'-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?')
ATTRIBUTE = re.compile(rb'([\w:]+)="([^"]*)"')

ODD_NUMBERS = [b'nan', b'NaN', b'inf', b'-inf', b'1e308', b'-1e308', b'1e999', b'0', b'-0', b'-1',
               b'1e-320', b'', b' ', b'x', b'1 2', b'0x10', b'1,5', b'++1']
ODD_VALUES = [b'', b' ', b'nonexistent', b'world', b'__model__', b'base_link', b'chassis', b'a::b',
              b'/', b'0 0 0', b'nan nan nan', b'1e308 0 0', b'libgazebo_ros_diff_drive.so',
              b'libgazebo_ros_camera.so', b'camera', b'ray', b'fixed', b'continuous', b'floating']
SNIPPETS = [b'<', b'>', b'/>', b'"', b'&', b'&amp;', b'&bogus;', b'<![CDATA[', b']]>', b'<!--', b'-->',
            b'\x00', b'\xff\xfe', b'\xc3', b'<model name="m">', b'</model>', b'<link name="l">',
            b'</link>', b'<pose>1 2 3 0 0 0</pose>', b'<pose>nan</pose>', b'<static>1</static>',
            b'<sphere><radius>0.1</radius></sphere>', b'<box><size>-1 0 1</size></box>',
            b'<joint name="j" type="continuous"><parent link="x"/><child link="y"/></joint>',
            b'<gazebo reference="nowhere"><sensor type="camera" name="s"/></gazebo>',
            b'<?xml version="1.0"?>', b'<!DOCTYPE sdf [<!ENTITY e "ee">]>', b'&e;']


def _replace(data, start, end, new):
    return data[:start] + new + data[end:]


@st.composite
def mutation(draw, data):
    # Mostly mutations that keep the XML well-formed, so the loaders' own checks are reached.
    kind = draw(st.sampled_from(['delete', 'insert', 'rename_tag', 'swap_tags', 'swap_tags', 'number',
                                 'number', 'number', 'attribute', 'attribute', 'duplicate']))
    size = len(data)
    if kind == 'delete':
        start = draw(st.integers(0, size))
        return data[:start] + data[start + draw(st.integers(1, 64)):]
    if kind == 'insert':
        at = draw(st.integers(0, size))
        return _replace(data, at, at, draw(st.sampled_from(SNIPPETS) | st.binary(min_size=1, max_size=8)))
    if kind == 'duplicate':
        # An element repeated as its own next sibling: duplicate names, second plugins...
        opening = [m for m in TAG.finditer(data) if not m.group(1)]
        if not opening:
            return data
        match = draw(st.sampled_from(opening))
        close = data.find(b'</' + match.group(2) + b'>', match.end())
        if close < 0:
            return data
        end = close + len(match.group(2)) + 3
        return _replace(data, end, end, data[match.start():end])
    if kind in ('rename_tag', 'swap_tags'):
        tags = list(TAG.finditer(data))
        if not tags:
            return data
        names = sorted({m.group(2) for m in tags})
        if kind == 'rename_tag':
            match = draw(st.sampled_from(tags))
            return _replace(data, match.start(2), match.end(2), draw(st.sampled_from(names)))
        # Every <a> becomes <b> and every <b> becomes <a>: still well-formed, different meaning.
        first, second = draw(st.sampled_from(names)), draw(st.sampled_from(names))
        swap = {first: second, second: first}
        return TAG.sub(lambda m: b'<' + m.group(1) + swap.get(m.group(2), m.group(2)), data)
    if kind == 'number':
        numbers = list(NUMBER.finditer(data))
        if not numbers:
            return data
        match = draw(st.sampled_from(numbers))
        new = draw(st.sampled_from(ODD_NUMBERS) | st.floats().map(lambda v: repr(v).encode()))
        return _replace(data, match.start(), match.end(), new)
    attributes = list(ATTRIBUTE.finditer(data))
    if not attributes:
        return data
    match = draw(st.sampled_from(attributes))
    if draw(st.booleans()):
        return _replace(data, match.start(), match.end(), b'')
    return _replace(data, match.start(2), match.end(2), draw(st.sampled_from(ODD_VALUES)))


@st.composite
def mutated(draw, base):
    data = base
    for _ in range(draw(st.integers(1, 4))):
        data = draw(mutation(data))
    return data


@st.composite
def mutated_world(draw):
    return draw(mutated(world_bytes(draw(st.integers(0, len(WORLD_FILES) - 1)))))


# A world that parses, but places a ball farther out than the physics takes.
FAR_BALL = (b'<sdf version="1.6"><world name="w"><model name="ball"><pose>100001 0 0.1 0 0 0</pose>'
            b'<link name="link"><collision name="c"><geometry><sphere><radius>0.1</radius></sphere>'
            b'</geometry></collision></link></model></world></sdf>')


@FUZZ
@given(mutated_world())
@example(FAR_BALL)
def test_mutated_worlds_load_or_raise_flatsim_error(data):
    load_world_into_simulation(data)


@FUZZ
@given(st.data())
def test_mutated_robot_loads_or_raises_flatsim_error(data):
    load_robot_into_simulation(data.draw(mutated(my_robot_urdf())))


# Generated trees ----------------------------------------------------------------------

NAMES = st.sampled_from(['a', 'b', 'c', 'ball', 'link', 'chassis', 'world', '__model__', 'a::b', ''])
SCALARS = ['0', '1', '-1', '0.1', '2', 'nan', 'inf', '-inf', '1e308', '1e-320', 'true', 'false', 'x', '']
VECTORS = ['0 0 1', '1 1 1', '0 0 0', '-1 1 1', '1 2', '1 2 3 4', 'nan 0 0', '1e308 1e308 1e308',
           '0 0 0 0 0 0', '1 2 0.5 0 0 1.57', '0 0 0 3.14159 0 0', '1 1 1 1', '0.5 0.5 0.5 1']
WORDS = ['Gazebo/White', 'Gazebo/Red', '__default__', 'model://ground_plane', 'model://sun',
         'model://somewhere', 'world', 'encoder', 'gaussian', 'R8G8B8', 'L8', 'cmd_vel', '/ns/topic']
TEXTS = st.sampled_from(SCALARS + VECTORS + WORDS) | st.lists(
    st.floats(width=32), max_size=7).map(lambda values: ' '.join(repr(v) for v in values))


def tree(children, leaves, vocabulary, attributes, required=None, max_depth=6):
    """XML elements that mostly follow the format's nesting, sometimes not.

    required: tag -> (child tags, attribute names) that an element nearly always has.
    """
    required = required or {}

    @st.composite
    def element(draw, tag, depth):
        required_children, required_attributes = required.get(tag, ((), ()))
        elem = ET.Element(tag, draw(st.fixed_dictionaries({}, optional=attributes)))
        for name in required_attributes:
            if draw(st.integers(0, 9)):
                elem.set(name, draw(attributes[name]))
        allowed = children.get(tag)
        if allowed and depth < max_depth:
            for child_tag in required_children:
                if draw(st.integers(0, 9)):
                    elem.append(draw(element(child_tag, depth + 1)))
            tags = st.sampled_from(allowed) | st.sampled_from(allowed) | st.sampled_from(vocabulary)
            for child_tag in draw(st.lists(tags, max_size=3)):
                elem.append(draw(element(child_tag, depth + 1)))
        elif tag in leaves or draw(st.booleans()):
            elem.text = draw(TEXTS)
        return elem
    return element


SDF_CHILDREN = {
    'sdf': ['world', 'model'],
    'world': ['model', 'include', 'state', 'physics', 'scene', 'gravity', 'frame', 'plugin', 'actor'],
    'model': ['link', 'model', 'joint', 'frame', 'pose', 'static', 'plugin', 'include'],
    'link': ['collision', 'visual', 'pose', 'inertial', 'sensor'],
    'collision': ['geometry', 'pose'],
    'visual': ['geometry', 'pose', 'material', 'transparency'],
    'geometry': ['box', 'cylinder', 'sphere', 'plane', 'mesh', 'polyline', 'empty', 'torus'],
    'box': ['size'], 'cylinder': ['radius', 'length'], 'sphere': ['radius'], 'plane': ['normal', 'size'],
    'mesh': ['uri'], 'material': ['ambient', 'diffuse', 'emissive', 'script'], 'script': ['name', 'uri'],
    'inertial': ['mass', 'pose'], 'state': ['model', 'insertions', 'deletions', 'link', 'pose', 'scale'],
    'insertions': ['model'], 'deletions': ['name'],
    'physics': ['max_step_size', 'real_time_factor', 'real_time_update_rate', 'gravity'],
    'scene': ['ambient', 'background'], 'joint': ['parent', 'child', 'pose'],
    'include': ['uri', 'name', 'pose'], 'frame': ['pose'],
}
SDF_LEAVES = {'pose', 'static', 'size', 'radius', 'length', 'normal', 'uri', 'ambient', 'diffuse',
              'emissive', 'name', 'mass', 'transparency', 'max_step_size', 'real_time_factor',
              'real_time_update_rate', 'gravity', 'background', 'parent', 'child', 'scale'}
SDF_VOCABULARY = sorted(set(SDF_CHILDREN) | SDF_LEAVES)
SDF_ATTRIBUTES = {'name': NAMES, 'relative_to': NAMES, 'frame': NAMES, 'attached_to': NAMES,
                  'version': st.sampled_from(['1.4', '1.6', '1.7', 'x']), 'default': TEXTS,
                  'filename': TEXTS, 'type': TEXTS, 'world_name': NAMES}
SDF_REQUIRED = {
    'model': ((), ('name',)), 'link': ((), ('name',)), 'collision': (('geometry',), ('name',)),
    'visual': (('geometry',), ('name',)), 'box': (('size',), ()), 'sphere': (('radius',), ()),
    'cylinder': (('radius', 'length'), ()),
}
sdf_element = tree(SDF_CHILDREN, SDF_LEAVES, SDF_VOCABULARY, SDF_ATTRIBUTES, SDF_REQUIRED)


@st.composite
def generated_world(draw):
    root = draw(st.sampled_from(['sdf', 'sdf', 'sdf', 'world', 'model']))
    elem = draw(sdf_element(root, 0))
    if root == 'sdf' and draw(st.booleans()):
        world = ET.SubElement(elem, 'world', name='w')
        world.extend(draw(st.lists(sdf_element('model', 2), min_size=1, max_size=4)))
    return ET.tostring(elem)


@FUZZ
@given(generated_world())
def test_generated_worlds_load_or_raise_flatsim_error(data):
    load_world_into_simulation(data)


@FUZZ
@given(generated_world())
def test_generated_model_sdf_loads_or_raises_flatsim_error(data):
    load_sdf_models(data)


URDF_CHILDREN = {
    'robot': ['link', 'link', 'joint', 'joint', 'gazebo', 'material'],
    'link': ['inertial', 'visual', 'collision'],
    'inertial': ['mass', 'origin', 'inertia'],
    'visual': ['origin', 'geometry', 'material'],
    'collision': ['origin', 'geometry'],
    'geometry': ['box', 'cylinder', 'sphere', 'mesh'],
    'joint': ['parent', 'child', 'origin', 'axis', 'limit'],
    'gazebo': ['plugin', 'sensor', 'material'],
    'plugin': ['leftJoint', 'rightJoint', 'leftFrontJoint', 'leftRearJoint', 'rightFrontJoint',
               'rightRearJoint', 'wheelSeparation', 'wheelDiameter', 'wheelAcceleration', 'wheelTorque',
               'torque', 'commandTopic', 'odometryTopic', 'robotNamespace', 'updateRate', 'publishTf',
               'publishOdomTF', 'broadcastTF', 'odometrySource', 'cameraName', 'imageTopicName',
               'frameName', 'topicName', 'hackBaseline', 'covariance_x', 'distortionK1'],
    'sensor': ['camera', 'ray', 'plugin', 'pose', 'update_rate'],
    'camera': ['horizontal_fov', 'image', 'clip'],
    'image': ['width', 'height', 'format'],
    'clip': ['near', 'far'],
    'ray': ['scan', 'range', 'noise'],
    'scan': ['horizontal'],
    'horizontal': ['samples', 'resolution', 'min_angle', 'max_angle'],
    'range': ['min', 'max', 'resolution'],
    'noise': ['type', 'mean', 'stddev'],
}
URDF_LEAVES = set(URDF_CHILDREN['plugin']) | {'pose', 'update_rate', 'horizontal_fov', 'width', 'height',
                                              'format', 'near', 'far', 'samples', 'resolution',
                                              'min_angle', 'max_angle', 'min', 'max', 'type', 'mean',
                                              'stddev'}
URDF_VOCABULARY = sorted(set(URDF_CHILDREN) | URDF_LEAVES)
ROBOT_LINKS = ['base', 'chassis', 'left_wheel', 'right_wheel', 'camera', 'hokuyo']
LINK_NAMES = st.sampled_from(ROBOT_LINKS + [''])
JOINT_NAMES = st.sampled_from(['left_wheel_hinge', 'right_wheel_hinge', 'camera_joint', 'j', ''])
URDF_ATTRIBUTES = {
    'name': LINK_NAMES | JOINT_NAMES, 'link': LINK_NAMES, 'reference': LINK_NAMES | JOINT_NAMES,
    'type': st.sampled_from(['fixed', 'continuous', 'revolute', 'prismatic', 'floating', 'planar',
                             'camera', 'depth', 'ray', 'gpu_ray', '']),
    'filename': st.sampled_from(['libgazebo_ros_diff_drive.so', 'libgazebo_ros_skid_steer_drive.so',
                                 'libgazebo_ros_camera.so', 'libgazebo_ros_openni_kinect.so',
                                 'libgazebo_ros_laser.so', 'libgazebo_ros_gpu_laser.so',
                                 'package://x/mesh.dae', '']),
    'xyz': st.sampled_from(VECTORS) | TEXTS, 'rpy': st.sampled_from(VECTORS) | TEXTS,
    'size': st.sampled_from(VECTORS) | TEXTS, 'radius': TEXTS, 'length': TEXTS, 'value': TEXTS,
}
URDF_REQUIRED = {
    'link': ((), ('name',)), 'joint': ((), ('name', 'type')), 'collision': (('geometry',), ()),
    'visual': (('geometry',), ()), 'box': ((), ('size',)), 'cylinder': ((), ('radius', 'length')),
    'sphere': ((), ('radius',)), 'mass': ((), ('value',)), 'parent': ((), ('link',)),
    'child': ((), ('link',)), 'sensor': ((), ('type', 'name')), 'plugin': ((), ('filename', 'name')),
    'ray': (('scan',), ()), 'scan': (('horizontal',), ()), 'camera': (('image',), ()),
}
urdf_element = tree(URDF_CHILDREN, URDF_LEAVES, URDF_VOCABULARY, URDF_ATTRIBUTES, URDF_REQUIRED)


@st.composite
def generated_robot(draw):
    """Mostly a tree of links joined by joints, with generated parts inside and <gazebo> tags."""
    if draw(st.integers(0, 19)) == 0:
        return ET.tostring(draw(urdf_element(draw(st.sampled_from(URDF_VOCABULARY)), 0)))
    robot = ET.Element('robot', name='fuzzed')
    links = draw(st.lists(st.sampled_from(ROBOT_LINKS), min_size=1, max_size=5, unique=True))
    for name in links:
        link = draw(urdf_element('link', 1))
        link.set('name', name)
        robot.append(link)
    for index, child in enumerate(links[1:], 1):
        joint = draw(urdf_element('joint', 1))
        joint.set('name', draw(JOINT_NAMES))
        if draw(st.integers(0, 4)):
            for tag in ('parent', 'child'):
                for old in joint.findall(tag):
                    joint.remove(old)
            ET.SubElement(joint, 'parent', link=links[draw(st.integers(0, index - 1))])
            ET.SubElement(joint, 'child', link=child)
        robot.append(joint)
    for _ in range(draw(st.integers(0, 3))):
        gazebo = draw(urdf_element('gazebo', 1))
        if draw(st.booleans()):
            gazebo.set('reference', draw(LINK_NAMES))
        robot.append(gazebo)
    return ET.tostring(robot)


@FUZZ
@given(generated_robot())
def test_generated_robots_load_or_raise_flatsim_error(data):
    load_robot_into_simulation(data)


@pytest.mark.parametrize('index', range(len(WORLD_FILES)), ids=[p.name for p in WORLD_FILES])
def test_the_unmutated_worlds_build(index):
    if WORLD_FILES[index].name == 'malformed.world':
        with pytest.raises(FlatsimError):
            parse_world(world_bytes(index))
    else:
        assert Simulation(parse_world(world_bytes(index))).models


def test_the_unmutated_robot_spawns():
    sim = Simulation()
    sim.spawn_robot('my_robot', load_robot(my_robot_urdf()), Pose())
    assert sim.robots()[0].drive is not None


# Inputs the fuzzer found, kept as regression tests -----------------------------------

@pytest.mark.parametrize('tag, value, message', [
    ('samples', '1e308', 'scan/horizontal/samples> is 1e+308, more than flatsim simulates (100000)'),
    ('samples', '4418379454.0', 'scan/horizontal/samples> is 4.41838e+09, more than flatsim simulates'),
    ('resolution', '1e308', 'gives inf ranges (samples 720 x resolution 1e+308)'),
    ('resolution', 'nan', 'resolution> is \'nan\', not a finite number'),
    ('width', '1e9', 'image/width> is 1e+09, more than flatsim simulates (16384)'),
    ('height', '16385', 'image/height> is 16385, more than flatsim simulates (16384)'),
])
def test_sensors_too_large_to_simulate_are_refused(tag, value, message):
    data = re.sub(rb'<%s>[^<]*</%s>' % (tag.encode(), tag.encode()),
                  b'<%s>%s</%s>' % (tag.encode(), value.encode(), tag.encode()), my_robot_urdf(), count=1)
    assert data != my_robot_urdf()
    with pytest.raises(FlatsimError, match=re.escape(message)):
        load_robot(data)


def test_a_footprint_of_one_float32_point_gets_the_small_square():
    spec = load_robot(b'<robot name="fuzzed"><link name="base"><collision><geometry>'
                      b'<cylinder radius="1e-320" length="0"/></geometry></collision></link></robot>')
    assert sorted(spec.footprint) == [(-0.05, -0.05), (-0.05, 0.05), (0.05, -0.05), (0.05, 0.05)]
    Simulation().spawn_robot('fuzzed', spec, Pose())


def test_a_robot_larger_than_flatsim_simulates_is_refused():
    with pytest.raises(FlatsimError, match='reaches 5e[+]307 m from the root link; flatsim simulates robots '
                       'within 1e[+]06 m'):
        load_robot(b'<robot name="fuzzed"><link name="base"><collision><geometry>'
                   b'<box size="1e308 1e308 1e308"/></geometry></collision></link></robot>')


def test_a_small_sphere_far_above_the_floor_builds():
    # Its centre -/+ radius rounds by more than 1e-9 m at 8.4e6 m.
    world = parse_world(b'<sdf version="1.6"><world name="w"><model name="m"><static>1</static>'
                        b'<link name="l"><collision name="c"><pose>0 0 8388609.0 0 0 0</pose>'
                        b'<geometry><sphere><radius>0.05</radius></sphere></geometry></collision>'
                        b'</link></model></world></sdf>')
    Simulation(world).step()


@pytest.mark.parametrize('change', [(b'<radius>0.1</radius>', b'<radius>1e-300</radius>'),
                                    (b'<update_rate>', b'<update_rate>1e300</update_rate><x>')])
def test_tiny_balls_and_absurd_rates_load_or_are_refused(change):
    for index in range(len(WORLD_FILES)):
        data = world_bytes(index).replace(*change)
        try:
            sim = Simulation(parse_world(data))
        except FlatsimError:
            continue
        for _ in range(10):
            sim.step()
