"""Meshes (STL, OBJ, Collada): read, covered with boxes, drawn by the camera, seen by lidars.

Every mesh here is written by the test itself, as ASCII STL, OBJ or a minimal Collada
document, from boxes whose sizes the assertions know.
"""
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from flatsim.loading import meshes
from flatsim.loading.config import CameraConfig, LaserConfig
from flatsim.loading.sdf_world import parse_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.sensors.camera import PinholeCamera
from flatsim.sensors.lidar import Lidar
from flatsim.world.sim import Simulation

CATKIN_SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
HOKUYO = os.path.join(CATKIN_SRC, 'my_robot', 'meshes', 'hokuyo.dae')

# -- writing meshes ------------------------------------------------------------------

CORNERS = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
# The twelve triangles of a cube on CORNERS, two per face, wound outwards.
CUBE_FACES = np.array([[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1],
                       [2, 3, 7], [2, 7, 6], [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]])


def box(size, centre=(0.0, 0.0, 0.0)):
    """(vertices, faces) of a box."""
    return CORNERS * np.asarray(size) + np.asarray(centre), CUBE_FACES.copy()


def joined(*parts):
    vertices, faces = [], []
    for part_vertices, part_faces in parts:
        faces.append(part_faces + sum(len(v) for v in vertices))
        vertices.append(part_vertices)
    return np.vstack(vertices), np.vstack(faces)


def table(top=(1.0, 0.8, 0.04), height=0.75, leg=0.05):
    """A table as one mesh: a top whose upper face is at height, four square legs."""
    sx, sy, sz = top
    parts = [box(top, (0.0, 0.0, height - sz / 2))]
    for x in (-1, 1):
        for y in (-1, 1):
            parts.append(box((leg, leg, height - sz), (x * (sx - leg) / 2, y * (sy - leg) / 2,
                                                       (height - sz) / 2)))
    return joined(*parts)


def write_stl(path, vertices, faces):
    lines = ['solid fixture']
    for face in faces:
        lines += ['facet normal 0 0 0', 'outer loop']
        lines += ['vertex %r %r %r' % tuple(vertices[index]) for index in face]
        lines += ['endloop', 'endfacet']
    lines.append('endsolid fixture')
    path.write_text('\n'.join(lines) + '\n')
    return str(path)


def write_obj(path, vertices, faces):
    lines = ['v %r %r %r' % tuple(vertex) for vertex in vertices]
    lines += ['f %d %d %d' % tuple(face + 1) for face in faces]
    path.write_text('\n'.join(lines) + '\n')
    return str(path)


def write_dae(path, vertices, faces, translate=(0.0, 0.0, 0.0), color=None):
    """A minimal Collada 1.4.1 document: one geometry, placed by a node's <translate>."""
    material = ''
    bind = ''
    if color is not None:
        material = textwrap.dedent('''\
            <library_effects><effect id="paint"><profile_COMMON><technique sid="common"><phong>
              <diffuse><color>%s %s %s 1</color></diffuse>
            </phong></technique></profile_COMMON></effect></library_effects>
            <library_materials><material id="paint-material"><instance_effect url="#paint"/>
            </material></library_materials>''') % tuple(color)
        bind = ('<bind_material><technique_common><instance_material symbol="paint" '
                'target="#paint-material"/></technique_common></bind_material>')
    path.write_text(textwrap.dedent('''\
        <?xml version="1.0" encoding="utf-8"?>
        <COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
          <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
          %s
          <library_geometries><geometry id="shape" name="shape"><mesh>
            <source id="positions">
              <float_array id="positions-array" count="%d">%s</float_array>
              <technique_common><accessor source="#positions-array" count="%d" stride="3">
                <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
              </accessor></technique_common>
            </source>
            <vertices id="shape-vertices"><input semantic="POSITION" source="#positions"/></vertices>
            <triangles count="%d"%s><input semantic="VERTEX" source="#shape-vertices" offset="0"/>
              <p>%s</p></triangles>
          </mesh></geometry></library_geometries>
          <library_visual_scenes><visual_scene id="scene">
            <node id="part" name="part"><translate>%r %r %r</translate>
              <instance_geometry url="#shape">%s</instance_geometry></node>
          </visual_scene></library_visual_scenes>
          <scene><instance_visual_scene url="#scene"/></scene>
        </COLLADA>
        ''') % (material, vertices.size, ' '.join(repr(float(v)) for v in vertices.ravel()),
                len(vertices), len(faces), ' material="paint"' if color is not None else '',
                ' '.join(str(int(i)) for i in faces.ravel()), *translate, bind))
    return str(path)


WRITERS = {'stl': write_stl, 'obj': write_obj, 'dae': write_dae}


def sizes_of(boxes):
    """Each box's (x, y) extents along the world axes (boxes turned by a quarter turn read
    the same), its z span and centre, rounded."""
    found = []
    for item in boxes:
        sx, sy, sz = item.size
        if abs(math.sin(item.pose.yaw)) > 0.5:
            sx, sy = sy, sx
        found.append(tuple(round(v, 6) + 0.0 for v in (item.pose.x, item.pose.y, sx, sy,
                                                       item.pose.z - sz / 2, item.pose.z + sz / 2)))
    return sorted(found)


# -- reading and covering ---------------------------------------------------------------

@pytest.mark.parametrize('kind', ['stl', 'obj', 'dae'])
def test_a_box_mesh_of_each_format_is_covered_by_exactly_that_box(tmp_path, kind):
    path = WRITERS[kind](tmp_path / ('chassis.' + kind), *box((0.4, 0.2, 0.1), (0.1, -0.2, 0.3)))
    assert sizes_of(meshes.mesh_boxes(path)) == [(0.1, -0.2, 0.4, 0.2, 0.25, 0.35)]


def test_scale_and_the_callers_frame_place_the_boxes(tmp_path):
    path = write_obj(tmp_path / 'unit.obj', *box((1.0, 1.0, 1.0)))
    frame = Pose(2.0, 0.0, 0.5, 0.0, 0.0, math.pi / 2).matrix()
    (only,) = meshes.mesh_boxes(path, (0.4, 0.2, 0.1), frame)
    # Turned a quarter turn, the 0.4 m side runs along y.
    assert sizes_of([only]) == [(2.0, 0.0, 0.2, 0.4, 0.45, 0.55)]


def test_a_collada_nodes_transform_moves_its_geometry(tmp_path):
    path = write_dae(tmp_path / 'moved.dae', *box((0.2, 0.2, 0.2)), translate=(1.0, 0.0, 0.1))
    assert sizes_of(meshes.mesh_boxes(path)) == [(1.0, 0.0, 0.2, 0.2, 0.0, 0.2)]


def test_a_collada_unit_scales_the_mesh_as_gazebo_does(tmp_path):
    path = write_dae(tmp_path / 'inches.dae', *box((10.0, 20.0, 40.0), (0.0, 0.0, 20.0)))
    with open(path) as stream:
        text = stream.read().replace('meter="1"', 'meter="0.0254"')
    with open(path, 'w') as stream:
        stream.write(text)
    (only,) = meshes.mesh_boxes(path)
    assert sizes_of([only]) == [(0.0, 0.0, 0.254, 0.508, 0.0, 1.016)]


def test_a_table_mesh_parts_into_its_legs_and_its_top(tmp_path):
    path = write_stl(tmp_path / 'table.stl', *table())
    found = sizes_of(meshes.mesh_boxes(path))
    legs = [(x, y, 0.05, 0.05, 0.0, 0.71) for x in (-0.475, 0.475) for y in (-0.375, 0.375)]
    assert found == sorted(legs + [(0.0, 0.0, 1.0, 0.8, 0.71, 0.75)])


def test_a_mesh_of_many_pieces_is_covered_more_coarsely(tmp_path):
    grains = joined(*[box((0.01, 0.01, 0.01), (0.02 * i, 0.0, 0.005)) for i in range(100)])
    boxes = meshes.cover(*grains)
    assert len(boxes) == 1
    assert sizes_of(boxes) == [(0.99, 0.0, 1.99, 0.01, 0.0, 0.01)]


@pytest.mark.parametrize('name, content, words', [
    ('cut_short.stl', b'binary STL header'.ljust(80) + b'\xe8\x03\0\0' + b'\xff' * 10,
     'holds no triangles'),
    ('broken.obj', 'v 0 0 0\nv 1 0 x\nf 1 2 3\n', 'cannot be read as OBJ'),
    ('empty.obj', '# nothing\n', 'holds no triangles'),
    ('mesh.ply', 'ply\n', 'is not an STL, OBJ or Collada (.dae) file'),
    ('bomb.dae', '<?xml version="1.0"?><!DOCTYPE c [<!ENTITY a "aaaa">]><COLLADA>&a;</COLLADA>',
     'declares XML entities'),
    ('broken.dae', '<COLLADA><library_geometries>', 'cannot be read as DAE'),
])
def test_a_mesh_that_cannot_be_read_says_why(tmp_path, name, content, words):
    if isinstance(content, bytes):
        (tmp_path / name).write_bytes(content)
    else:
        (tmp_path / name).write_text(content)
    with pytest.raises(meshes.MeshError) as caught:
        meshes.mesh_boxes(str(tmp_path / name))
    assert words in str(caught.value)


def test_uris_resolve_as_gazebo_resolves_them(tmp_path, monkeypatch):
    models = tmp_path / 'models'
    (models / 'crate' / 'meshes').mkdir(parents=True)
    crate = write_stl(models / 'crate' / 'meshes' / 'crate.stl', *box((1, 1, 1)))
    package = tmp_path / 'src' / 'my_bot'
    (package / 'meshes').mkdir(parents=True)
    (package / 'package.xml').write_text('<package format="2"><name>my_bot</name><version>1.0.0'
                                         '</version><description>d</description><maintainer '
                                         'email="a@b.c">a</maintainer><license>BSD</license>'
                                         '</package>')
    body = write_stl(package / 'meshes' / 'body.stl', *box((1, 1, 1)))
    monkeypatch.setenv('ROS_PACKAGE_PATH', str(tmp_path / 'src'))
    paths = [str(models)]
    assert meshes.find_mesh('model://crate/meshes/crate.stl', model_paths=paths) == crate
    assert meshes.find_mesh('package://my_bot/meshes/body.stl', model_paths=paths) == body
    # gazebo_ros puts exported packages on the model path: model:// finds a package too.
    assert meshes.find_mesh('model://my_bot/meshes/body.stl', model_paths=paths) == body
    assert meshes.find_mesh('file://' + crate, model_paths=paths) == crate
    assert meshes.find_mesh('meshes/crate.stl', str(models / 'crate'), paths) == crate
    with pytest.raises(meshes.MeshNotFound, match='file not found'):
        meshes.find_mesh('model://crate/meshes/missing.stl', model_paths=paths)


def test_the_course_hokuyo_is_covered_by_its_housing(tmp_path):
    boxes = meshes.mesh_boxes(HOKUYO)
    # my_robot.xacro: "Must match the extents of meshes/hokuyo.dae": 0.05 x 0.05 x 0.07 m.
    low = min(b.pose.z - b.size[2] / 2 for b in boxes)
    high = max(b.pose.z + b.size[2] / 2 for b in boxes)
    assert high - low == pytest.approx(0.07, abs=1e-6)
    assert max(max(b.size[:2]) for b in boxes) == pytest.approx(0.05, abs=1e-6)


# -- robots --------------------------------------------------------------------------

def mesh_robot(uri, name='mesher', lidar=False):
    """A two-wheeled robot whose chassis is only a mesh (visual and collision)."""
    sensor = '''
      <link name="laser"><collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision></link>
      <joint name="laser_joint" type="fixed"><parent link="chassis"/><child link="laser"/>
        <origin xyz="0 0 0.1"/></joint>
      <gazebo reference="laser"><sensor type="ray" name="scanner"><update_rate>10</update_rate>
        <ray><scan><horizontal><samples>181</samples><min_angle>-1.5707963</min_angle>
        <max_angle>1.5707963</max_angle></horizontal></scan><range><min>0.1</min><max>10</max></range>
        </ray><plugin name="l" filename="libgazebo_ros_laser.so"><topicName>/scan</topicName>
        <frameName>laser</frameName></plugin></sensor></gazebo>''' if lidar else ''
    return '''<robot name="%s">
      <link name="chassis">
        <visual><geometry><mesh filename="%s"/></geometry></visual>
        <collision><geometry><mesh filename="%s"/></geometry></collision>
      </link>%s
    </robot>''' % (name, uri, uri, sensor)


def test_a_mesh_chassis_has_the_footprint_of_its_mesh(tmp_path):
    path = write_dae(tmp_path / 'chassis.dae', *box((0.4, 0.2, 0.1), (0.0, 0.0, 0.1)))
    spec = load_robot(mesh_robot('file://' + path))
    # Collada keeps its numbers as 32-bit floats.
    xs = sorted({round(x, 6) for x, _ in spec.footprint})
    ys = sorted({round(y, 6) for _, y in spec.footprint})
    assert xs == [-0.2, 0.2] and ys == [-0.1, 0.1]
    assert not [item for item in spec.skipped if 'mesh' in str(item)]


def test_a_mesh_chassis_is_seen_by_another_robots_lidar_at_the_analytic_distance(tmp_path):
    path = write_stl(tmp_path / 'chassis.stl', *box((0.4, 0.2, 0.1), (0.0, 0.0, 0.1)))
    sim = Simulation()
    sim.spawn_robot('target', load_robot(mesh_robot('file://' + path, 'target')), Pose(3.0, 0.0))
    watcher = sim.spawn_robot('watcher', load_robot(mesh_robot('file://' + path, 'watcher', lidar=True)),
                              Pose(0.0, 0.0))
    (slot,) = watcher.sensors
    ranges = sim.sense(slot)
    ahead = ranges[len(ranges) // 2]
    # The lidar sits on the watcher's origin; the target's near face is 0.2 m before its centre.
    assert ahead == pytest.approx(3.0 - 0.2, abs=1e-6)
    # Turned a quarter turn, the target shows its 0.1 m half width instead.
    sim.set_model_state('target', Pose(3.0, 0.0, 0.0, 0.0, 0.0, math.pi / 2))
    assert sim.sense(slot)[len(ranges) // 2] == pytest.approx(3.0 - 0.1, abs=1e-6)
    # A lidar never sees its own robot: with the target gone, nothing is there.
    sim.delete_model('target')
    assert np.isinf(sim.sense(slot)).all()


def test_a_link_with_only_a_mesh_visual_collides_by_it_and_the_hokuyo_is_drawn(tmp_path):
    path = write_obj(tmp_path / 'shell.obj', *box((0.3, 0.3, 0.2), (0.0, 0.0, 0.1)))
    spec = load_robot('''<robot name="r">
      <link name="base"><visual><geometry><mesh filename="file://%s"/></geometry></visual></link>
      <link name="hokuyo"><visual><geometry><mesh filename="file://%s"/></geometry></visual>
        <collision><geometry><box size="0.05 0.05 0.07"/></geometry></collision></link>
      <joint name="j" type="fixed"><parent link="base"/><child link="hokuyo"/>
        <origin xyz="0 0 0.3"/></joint>
    </robot>''' % (path, HOKUYO))
    assert [kind for kind, _, _ in spec.links['base'].collisions] == ['box']
    assert sorted({round(abs(v), 9) for point in spec.footprint for v in point}) == [0.15]
    assert spec.links['hokuyo'].visuals and all(kind == 'box' for kind, _, _ in spec.links['hokuyo'].visuals)


def test_a_robot_visual_mesh_that_is_missing_is_drawn_by_its_collisions_with_one_warning():
    spec = load_robot('''<robot name="r">
      <link name="base"><visual><geometry><mesh filename="package://nowhere/meshes/base.dae"/></geometry>
        </visual><collision><geometry><box size="0.3 0.2 0.1"/></geometry></collision></link>
    </robot>''')
    assert [(kind, size) for kind, _, size in spec.links['base'].visuals] == [('box', (0.3, 0.2, 0.1))]
    (record,) = [item for item in spec.skipped if 'mesh' in str(item)]
    assert record.subject == 'visual meshes not found'
    assert record.reason == 'drawn by their collisions instead: base (package://nowhere/meshes/base.dae)'


# -- worlds --------------------------------------------------------------------------

def world_sdf(body):
    return '<sdf version="1.6"><world name="w">%s</world></sdf>' % body


def camera_config(width=200, height=150):
    return CameraConfig(sensor_name='eye', width=width, height=height, hfov=1.2, near=0.05, far=50.0)


def test_a_table_drawn_only_by_its_mesh_is_seen_by_the_camera_and_stops_the_robot(tmp_path):
    path = write_dae(tmp_path / 'table.dae', *table(), color=(0.8, 0.1, 0.1))
    spec = parse_world(world_sdf("""
      <model name="table"><static>true</static><pose>3 0 0 0 0 0</pose>
        <link name="link"><visual name="visual"><geometry><mesh><uri>file://%s</uri></mesh>
        </geometry></visual></link></model>""" % path))
    assert not spec.skipped
    sim = Simulation(spec)
    image = PinholeCamera(camera_config()).render(sim.scene, 0.0, 0.0, 0.3, 0.0).astype(int)
    # Drawn in the mesh's own red: the top (0.71 to 0.75 m) above the camera's horizon, the
    # legs below it.
    red_rows = np.flatnonzero((image[:, :, 0] > 2 * image[:, :, 1] + 20).any(axis=1))
    assert red_rows.size and red_rows.min() < 70 and red_rows.max() > 80
    # The legs cut the working height and collide; the top is above it and does not.
    assert len(sim.models['table'].colliders) == 4
    # The lidar at 0.1 m sees the near leg, not the top, and passes between the legs.
    angle = math.atan2(0.375, 2.525)
    lidar = Lidar(LaserConfig(samples=2, min_angle=0.0, max_angle=angle, range_min=0.05,
                              range_max=10.0))
    between, leg = lidar.scan(sim.scene, 0.0, 0.0, 0.1, 0.0)
    assert np.isinf(between)
    assert leg == pytest.approx(2.5 / math.cos(angle), abs=1e-5)
    assert lidar.scan(sim.scene, 0.0, 0.0, 0.73, 0.0)[0] == pytest.approx(2.5, abs=1e-5)


def test_a_database_link_without_its_mesh_is_drawn_by_its_collision_and_named():
    spec = parse_world(world_sdf("""
      <model name="cafe_table"><static>1</static><pose>2 0 0 0 0 0</pose>
        <link name="link">
          <collision name="surface"><pose>0 0 0.755 0 0 0</pose>
            <geometry><box><size>0.913 0.913 0.04</size></box></geometry></collision>
          <collision name="column"><pose>0 0 0.37 0 0 0</pose>
            <geometry><box><size>0.042 0.042 0.74</size></box></geometry></collision>
          <visual name="visual"><geometry><mesh><uri>model://cafe_table/meshes/cafe_table.dae</uri>
            </mesh></geometry></visual>
        </link></model>"""), model_paths=[])
    notes = [str(item) for item in spec.skipped]
    assert notes == ['visual meshes not found: drawn by their collisions instead: '
                     'cafe_table::link (model://cafe_table/meshes/cafe_table.dae)']
    camera = PinholeCamera(camera_config())
    image = camera.render(Simulation(spec).scene, 0.0, 0.0, 0.3, 0.0)
    empty = camera.render(Simulation().scene, 0.0, 0.0, 0.3, 0.0)
    # The column stands in the middle of the view from the floor (row 97) to 0.74 m (row 43).
    drawn = (image[:, 100] != empty[:, 100]).any(axis=1)
    assert drawn[45:96].all() and not drawn[100:].any()


def test_the_studio_draws_a_robots_mesh_and_a_mesh_table(tmp_path):
    from flatsim.studio.world import describe_scene
    path = write_stl(tmp_path / 'table.stl', *table())
    sim = Simulation(parse_world(world_sdf("""
      <model name="table"><static>true</static><pose>3 0 0 0 0 0</pose>
        <link name="link"><visual name="visual"><geometry><mesh><uri>%s</uri></mesh>
        </geometry></visual></link></model>""" % path)))
    sim.spawn_robot('bot', load_robot('''<robot name="bot"><link name="hokuyo">
        <visual><geometry><mesh filename="file://%s"/></geometry></visual>
        <collision><geometry><box size="0.05 0.05 0.07"/></geometry></collision></link></robot>'''
                                      % HOKUYO), Pose())
    models = {model['name']: model for model in describe_scene(sim)['models']}
    table_shapes = models['table']['links'][0]['shapes']
    assert sorted(round(shape['size'][2], 3) for shape in table_shapes) == [0.04] + [0.71] * 4
    (hokuyo,) = models['bot']['links']
    assert {shape['shape'] for shape in hokuyo['shapes']} == {'box'}
    assert max(shape['size'][0] for shape in hokuyo['shapes']) == pytest.approx(0.05, abs=1e-5)


def test_numba_is_loaded_for_the_first_mesh_covered_not_for_a_world_without_one():
    """`gazebo WORLD` reads the world beside the simulator to say what is wrong with it, while
    the simulator and roscore start on the same CPUs: it should not spend a fifth of a second
    importing numba for a world that has no mesh."""
    world = os.path.join(CATKIN_SRC, 'my_robot', 'worlds', 'chase_house.world')
    code = textwrap.dedent('''
        import sys
        import numpy as np
        from flatsim.loading import meshes
        from flatsim.loading.sdf_world import load_world
        load_world(%r)
        print('numba' in sys.modules)
        meshes.cover(np.eye(3), np.array([[0, 1, 2]]))
        print('numba' in sys.modules)
    ''' % world)
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ['False', 'True'], out.stderr
