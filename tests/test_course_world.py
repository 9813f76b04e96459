"""The course's simple_arm world in flatsim: its number blocks are drawn as
stand-ins, where the lesson's arm pose looks, with digits a student reads."""
import os
import pathlib
import re

import numpy as np

from course_blocks import BLOCK_CENTRES, BLOCK_SIDE, FIXTURE, arm_camera, face_corner, front_glyph, project
from flatsim.loading.sdf_world import load_world
from flatsim.loading.stand_ins import PIXEL_FONT
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation

TOP = pathlib.Path(__file__).resolve().parent.parent
SKY = 178          # Gazebo's default background grey, 0.7


def course_arm(monkeypatch):
    # The course's URDF finds its gazebo.xacro through $(find simple_arm): this fixture's own
    # folder, as tests/fixtures holds other packages of that name.
    monkeypatch.setenv('ROS_PACKAGE_PATH', '%s:%s' % (FIXTURE, os.environ.get('ROS_PACKAGE_PATH', '')))
    world = load_world(os.path.join(FIXTURE, 'worlds', 'willow_garage.world'))
    sim = Simulation(world)
    spec = load_robot(expand_xacro(os.path.join(FIXTURE, 'urdf', 'simple_arm.urdf.xacro')),
                      name='simple_arm')
    robot = sim.spawn_robot('simple_arm', spec, Pose())
    return world, sim, robot


def test_the_loader_says_which_meshes_became_stand_ins_and_which_were_left_out(monkeypatch):
    world, _sim, _robot = course_arm(monkeypatch)
    reports = [str(item) for item in world.skipped]
    for digit in (1, 2, 3):
        assert ('number%d/link/visual: mesh model://number1/meshes/number.dae cannot be read; drawn '
                'as a stand-in instead: a white 0.40 m cube with the digit %d on its faces'
                % (digit, digit)) in reports
    assert any(r.startswith('willowgarage/walls/visual: mesh model://willowgarage/meshes/'
                            'willowgarage_visual.dae file not found; left out')
               for r in reports), reports
    # The saved state's scale 0.5 is the meshes' own: nothing to report about it.
    assert not any('state scale' in r for r in reports), reports
    assert len(reports) == 5, reports


def test_the_course_gives_the_blocks_the_size_the_loader_reports(monkeypatch):
    world, _sim, _robot = course_arm(monkeypatch)
    logged = {re.search(r'a white ([0-9.]+) m cube', str(item)).group(1) for item in world.skipped
              if 'stand-in' in str(item)}
    course = re.sub(r'\s+', ' ', (TOP / 'docs' / 'course.md').read_text())
    told = re.findall(r'number blocks .{0,80}? as white ([0-9.]+) m (?:cubes|boxes)', course)
    assert logged == {'%.2f' % BLOCK_SIDE}
    assert told == ['%.2f' % BLOCK_SIDE], told


def test_the_camera_sees_only_sky_with_the_arm_upright(monkeypatch):
    _world, sim, robot = course_arm(monkeypatch)
    image = sim.sense(robot.sensors[0])
    assert (image == SKY).all()


def test_at_the_lessons_pose_the_camera_reads_1_2_3_on_the_blocks(monkeypatch):
    _world, sim, robot = course_arm(monkeypatch)
    slot = robot.sensors[0]
    robot.control.articulation.position[:] = (1.57, 1.57)
    eye, axes = arm_camera(1.57, 1.57)
    pose = sim.sensor_pose(slot)
    assert np.allclose(eye, (pose.x, pose.y, pose.z), atol=1e-6)
    image = sim.sense(slot)
    for digit in (1, 2, 3):
        assert front_glyph(image, digit, eye, axes) == PIXEL_FONT[digit], digit
        corner = face_corner(image, digit, eye, axes)
        assert corner.min() > 60 and tuple(corner) != (SKY, SKY, SKY), (digit, corner)
    # Left to right as the lesson shows them: 1, 2, 3, all inside the picture.
    columns = [project(BLOCK_CENTRES[digit], eye, axes)[0] for digit in (1, 2, 3)]
    assert 0 < columns[0] < columns[1] < columns[2] < 640
    # Beside each block, at its height, the sky: the blocks are where the world puts them.
    for digit, (x, y, z) in BLOCK_CENTRES.items():
        column, row = project((x + BLOCK_SIDE * 0.9, y - BLOCK_SIDE / 2, z + BLOCK_SIDE * 0.4), eye, axes)
        assert tuple(image[int(round(row)), int(round(column))]) == (SKY, SKY, SKY), digit

