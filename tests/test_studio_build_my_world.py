"""The course's Build My World path, whole, in a real browser with Gazebo's words and hotkeys,
from a fresh home folder, as docs/course.md's "Build the world" gives it:

    gazebo                                  # an empty world, its window in the page
        Edit > Building Editor: a house of four walls, a door and a window; File > Save As
        my_house; File > Exit Building Editor.
        Edit > Model Editor: the white ball (a sphere, radius 0.1, the four colours at 1);
        File > Save As my_ball; Exit; Insert my_ball in front of where the robot will stand.
        Insert > Cafe Table; `t` and a drag moves it, `r` and a drag turns it; Ctrl+Z takes
        the turn back and Ctrl+Shift+Z redoes it; my_ball deleted and Edit > Undo brings it back.
        File > Save World As ~/catkin_ws/src/my_robot/worlds/my_world.world.
    roslaunch my_robot world.launch world_file:=.../my_world.world gui:=false

Every step is checked in the simulator (/gazebo/get_model_state, get_link_state, the files it
wrote), and the relaunched world has the house's walls, the ball and the table where they were
saved, and the robot's camera sees the ball.
"""
import math
import os
import re
import signal
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from playwright.sync_api import expect

from rosproc import RosSystem
from studio_browser import (StudioWorld, browser_context, choose, drop, model_my_ball,  # noqa: F401
                            new_page, save_as, wait_for)
from test_studio import grab_handle, select
from test_studio_course_path import STARTUP_S, delete, printed_address

# The house: 6 m by 4 m around the origin, where world.launch spawns the robot facing +x.
CORNERS = [(-3.0, -2.0), (3.0, -2.0), (3.0, 2.0), (-3.0, 2.0), (-3.0, -2.0)]
DOOR_AT = (3.0, -1.0)            # on the east wall, out of the camera's middle
WINDOW_AT = (0.0, 2.0)           # on the north wall
# In front of the robot's camera, the floor clear between them.
BALL_AT = (1.5, 0.0)
# Behind the robot, away from the walls.
TABLE_AT = (-1.5, 1.0)
POSITION_M = 1e-3
ANGLE_RAD = 1e-3


def yaw_of(orientation):
    return 2.0 * math.atan2(orientation['z'], orientation['w'])


def pose(world, name, service='/gazebo/get_model_state'):
    """(x, y, z, yaw) of a model, or of a link with 'model::link', in the simulator."""
    if service == '/gazebo/get_link_state':
        state = world.call(service, 'gazebo_msgs/GetLinkState', {'link_name': name})
        assert state['success'], state['status_message']
        found = state['link_state']['pose']
    else:
        state = world.model_state(name)
        assert state['success'], state['status_message']
        found = state['pose']
    where = found['position']
    return where['x'], where['y'], where['z'], yaw_of(found['orientation'])


def same_pose(a, b):
    turn = abs(math.remainder(a[3] - b[3], 2 * math.pi))
    return max(abs(p - q) for p, q in zip(a[:3], b[:3])) <= POSITION_M and turn <= ANGLE_RAD


def floor_click(page, x, y):
    point = page.evaluate('([x, y]) => window.studio.buildingEditor.screenPoint(x, y)', [x, y])
    page.mouse.click(point['x'], point['y'])


def wall_links(sdf_path):
    return sorted(link.get('name') for link in ET.parse(str(sdf_path)).iter('link')
                  if re.fullmatch(r'Wall_\d+', link.get('name') or ''))


def draw_the_house(page, world, home):
    """Edit > Building Editor: four walls in a closed loop, a door and a window, saved as
    my_house and put into the world. Returns its wall links' names."""
    choose(page, 'Edit', 'Building Editor')
    editor = page.get_by_role('region', name='Building Editor')
    editor.get_by_role('button', name='Wall').click()
    for corner in CORNERS:
        floor_click(page, *corner)
    # Back at its start, the loop is closed and the next click starts a new wall.
    expect(editor.get_by_role('status', name='Building Editor hint')).to_contain_text('Click where the wall starts')
    page.keyboard.press('Escape')
    assert len(page.evaluate('() => window.studio.buildingEditor.design.walls')) == 4
    editor.get_by_role('button', name='Door').click()
    floor_click(page, *DOOR_AT)
    expect(editor.get_by_role('group', name='Door Inspector')).to_be_visible()
    editor.get_by_role('button', name='Window').click()
    floor_click(page, *WINDOW_AT)
    expect(editor.get_by_role('group', name='Window Inspector')).to_be_visible()
    kinds = page.evaluate('() => window.studio.buildingEditor.design.openings.map((o) => o.kind)')
    assert sorted(kinds) == ['door', 'window'], kinds
    expect(save_as(page, 'my_house')).to_have_count(0)
    sdf = home / 'building_editor_models' / 'my_house' / 'model.sdf'
    assert sdf.exists()
    walls = wall_links(sdf)
    assert len(walls) == 4, walls
    choose(page, 'File', 'Exit Building Editor')
    wait_for(lambda: 'my_house' in world.model_names())
    assert pose(world, 'my_house')[:2] == pytest.approx((0.0, 0.0), abs=POSITION_M)
    # The north wall stands on the drawn line, in the simulator.
    north = [pose(world, 'my_house::' + wall, '/gazebo/get_link_state') for wall in walls]
    assert any(abs(y - 2.0) < POSITION_M and abs(x) < POSITION_M for x, y, _z, _yaw in north), north
    return walls


def make_the_ball(page, world, home):
    """Edit > Model Editor: the white ball, saved as my_ball; Exit inserts it; it goes in front
    of where the robot will stand instead, from the Insert tab."""
    model_my_ball(page)
    expect(save_as(page, 'my_ball')).to_have_count(0)
    assert sorted(os.listdir(home / '.gazebo' / 'models' / 'my_ball')) == ['model.config', 'model.sdf']
    choose(page, 'File', 'Exit Model Editor')
    wait_for(lambda: 'my_ball' in world.model_names())
    delete(page, 'my_ball')
    wait_for(lambda: 'my_ball' not in world.model_names())
    page.get_by_role('tab', name='Insert').click()
    page.get_by_role('list', name=str(home / '.gazebo' / 'models')).get_by_role(
        'button', name='my_ball').click()
    drop(page, *BALL_AT)
    wait_for(lambda: 'my_ball' in world.model_names())
    assert pose(world, 'my_ball')[:2] == pytest.approx(BALL_AT, abs=0.05)


def insert_move_and_turn_the_table(page, world):
    """Insert > Cafe Table, then `t` and a drag, `r` and a drag: (dropped, moved, turned) poses."""
    page.get_by_role('tab', name='Insert').click()
    page.get_by_role('button', name='Cafe Table', exact=True).click()
    expect(page.get_by_role('status', name='Placing')).to_contain_text('place Cafe Table')
    drop(page, *TABLE_AT)
    wait_for(lambda: 'cafe_table' in world.model_names())
    dropped = pose(world, 'cafe_table')
    assert dropped[:2] == pytest.approx(TABLE_AT, abs=0.05)

    page.get_by_role('tab', name='World').click()
    point = grab_handle(page, 'cafe_table')          # select, `t`, the mouse down on the handle
    expect(page.get_by_role('button', name='Translation Mode')).to_have_attribute('aria-pressed', 'true')
    page.mouse.move(point['x'] + 80, point['y'] + 20, steps=8)
    page.mouse.up()
    wait_for(lambda: page.evaluate('() => window.studio.leases.cafe_table === undefined'))
    moved = wait_for(lambda: (lambda now: now if math.hypot(now[0] - dropped[0], now[1] - dropped[1]) > 0.2
                              else None)(pose(world, 'cafe_table')))
    assert moved[3] == pytest.approx(dropped[3], abs=ANGLE_RAD)

    page.keyboard.press('Escape')
    select(page, 'cafe_table')
    page.locator('#view').focus()
    page.keyboard.press('r')
    expect(page.get_by_role('button', name='Rotation Mode')).to_have_attribute('aria-pressed', 'true')
    ring = page.evaluate("() => window.studio.view.handlePoint('Z')")
    assert ring is not None, 'no rotation ring on cafe_table'
    page.mouse.move(ring['x'], ring['y'])
    page.mouse.down()
    page.mouse.move(ring['x'] + 60, ring['y'] + 60, steps=10)
    page.mouse.up()
    wait_for(lambda: page.evaluate('() => window.studio.leases.cafe_table === undefined'))
    turned = wait_for(lambda: (lambda now: now if abs(math.remainder(now[3] - moved[3], 2 * math.pi)) > 0.1
                               else None)(pose(world, 'cafe_table')))
    assert turned[:2] == pytest.approx(moved[:2], abs=POSITION_M)
    page.keyboard.press('Escape')
    return dropped, moved, turned


def test_build_my_world_from_a_fresh_home_and_relaunch_it_with_the_robot(tmp_path, browser_context):
    home = tmp_path / 'home'
    worlds = home / 'catkin_ws' / 'src' / 'my_robot' / 'worlds'
    worlds.mkdir(parents=True)
    saved = worlds / 'my_world.world'
    env = dict(os.environ, HOME=str(home), ROS_HOME=str(tmp_path / 'ros_home'), BROWSER='true')
    env.pop('DISPLAY', None)
    env.pop('WAYLAND_DISPLAY', None)
    # Not entered: gazebo and roslaunch start the master themselves, as they do for a student.
    ros = RosSystem(tmp_path, env=env)
    world = StudioWorld(ros, str(tmp_path / 'ros_home'))
    try:
        ros.run('gazebo', ['gazebo'])
        page = new_page(browser_context, wait_for(lambda: printed_address(ros, 'gazebo'), STARTUP_S))
        # An empty world: nothing of the student's yet.
        assert set(world.model_names()) <= {'ground_plane'}

        walls = draw_the_house(page, world, home)
        make_the_ball(page, world, home)
        dropped, moved, turned = insert_move_and_turn_the_table(page, world)

        # Ctrl+Z takes the turn back in the simulator, and Ctrl+Shift+Z turns it again.
        page.locator('#view').focus()
        page.keyboard.press('Control+z')
        wait_for(lambda: same_pose(pose(world, 'cafe_table'), moved))
        page.keyboard.press('Control+Shift+Z')
        wait_for(lambda: same_pose(pose(world, 'cafe_table'), turned))
        # A deleted ball comes back with Edit > Undo, where it was.
        ball = pose(world, 'my_ball')
        delete(page, 'my_ball')
        wait_for(lambda: 'my_ball' not in world.model_names())
        choose(page, 'Edit', 'Undo')
        wait_for(lambda: 'my_ball' in world.model_names())
        assert same_pose(pose(world, 'my_ball'), ball)

        before = {name: pose(world, name) for name in ('my_house', 'my_ball', 'cafe_table')}
        before.update({wall: pose(world, 'my_house::' + wall, '/gazebo/get_link_state') for wall in walls})
        choose(page, 'File', 'Save World As')
        dialog = page.get_by_role('dialog', name='Save World')
        dialog.get_by_role('button', name='Browse').click()
        chooser = page.get_by_role('dialog', name='Open Directory')
        folders = chooser.get_by_role('list', name='Folders')
        expect(chooser.get_by_role('status', name='Folder')).to_have_text(str(home))
        for folder in ('catkin_ws', 'src', 'my_robot', 'worlds'):
            folders.get_by_role('button', name=folder, exact=True).click()
        expect(chooser.get_by_role('status', name='Folder')).to_have_text(str(worlds))
        chooser.get_by_role('button', name='Choose').click()
        # The chooser closes once the simulator has allowed the folder; until then it is modal
        # and what is typed would not reach the Save World dialog.
        expect(chooser).to_have_count(0)
        expect(dialog.get_by_role('textbox', name='Location:')).to_have_value(str(worlds))
        dialog.get_by_role('textbox', name='File name:').fill('my_world.world')
        dialog.get_by_role('button', name='Save', exact=True).click()
        expect(dialog).to_have_count(0)
        expect(page.get_by_role('status', name='Messages')).to_contain_text('Saved the world in %s' % saved)
        assert page.errors == []
        page.close()
        ros.procs['gazebo'].send_signal(signal.SIGINT)
        assert ros.wait_exit('gazebo'), ros.log_tail('gazebo')

        ros.run('world', ['roslaunch', '-p', str(ros.port), 'my_robot', 'world.launch',
                          'world_file:=%s' % saved, 'gui:=false'])
        ros.graph.wait_for_service('/gazebo/get_model_state')
        wait_for(lambda: 'my_robot' in world.model_names(), STARTUP_S)
        after = {name: pose(world, name) for name in ('my_house', 'my_ball', 'cafe_table')}
        after.update({wall: pose(world, 'my_house::' + wall, '/gazebo/get_link_state') for wall in walls})
        moved_off = {name: (before[name], after[name]) for name in before
                     if not same_pose(before[name], after[name])}
        assert not moved_off, moved_off
        # The robot's camera sees the white ball: pure white pixels, in its middle third.
        image = world.message('/camera/rgb/image_raw', 'sensor_msgs/Image')
        pixels = np.frombuffer(image['data'], np.uint8).reshape(image['height'], image['width'], 3)
        white = np.argwhere((pixels == 255).all(axis=2))
        assert len(white) > 0
        assert image['width'] / 3 < white[:, 1].mean() < 2 * image['width'] / 3
    finally:
        ros.stop()
