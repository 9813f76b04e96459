"""The studio's editors in a real browser, on the project's robot in an empty world
(`roslaunch my_robot world.launch gui:=false world_file:=.../empty.world x:=-2`) with HOME
in a temporary folder, so that ~/.gazebo and the editors' folders are the test's own:
the course's my_ball from the Model Editor, inserted from the Insert tab and seen white by
the robot's camera; a house drawn in the Building Editor and seen by its lidar; Save World
As; and what the editors refuse. docs/course.md's pictures of them:

    STUDIO_SCREENSHOTS=docs python -m pytest tests/test_studio_editors.py

(without STUDIO_SCREENSHOTS they go to the tests' temporary folders)."""
import math
import os

import numpy as np
import pytest
from playwright.sync_api import expect

from flatsim.loading.sdf_world import load_world
from studio_browser import (browser_context, choose, drop, fill, model_my_ball, open_page,  # noqa: F401
                            save_as, screenshot, start_empty_world, wait_for)

# The house: 3 m by 3 m around the robot, walls 0.15 m thick, a door in its east wall.
CORNERS = [(-3.5, -1.5), (-0.5, -1.5), (-0.5, 1.5), (-3.5, 1.5), (-3.5, -1.5)]
EAST_X, NORTH_Y, HALF_THICKNESS = -0.5, 1.5, 0.075
DOOR_AT = (-0.5, 0.75)           # its centre; it is 0.9 m wide
LIDAR_NOISE = 0.03               # 3 standard deviations of my_robot's laser noise, m
# Where my_ball is dropped: in front of the robot's camera, away from the model's own pose (0, 0).
BALL_AT = (0.5, 0.0)


@pytest.fixture(scope='module')
def home(tmp_path_factory):
    home = tmp_path_factory.mktemp('home')
    (home / 'worlds').mkdir()
    broken = home / '.gazebo' / 'models' / 'broken'
    broken.mkdir(parents=True)
    (broken / 'model.config').write_text('<model><name>broken thing</name><sdf>model.sdf</sdf>')
    return home


@pytest.fixture(scope='module')
def studio_world(tmp_path_factory, home):
    with start_empty_world(tmp_path_factory.mktemp('studio'), home) as world:
        yield world


def position(world, model):
    state = world.model_state(model)
    assert state['success'], state['status_message']
    return state['pose']['position']


def log(world):
    return world.ros.log_tail('world', 200000)


def stepping(world):
    """The simulator goes on: sim time moves."""
    before = world.sim_time()
    wait_for(lambda: world.sim_time() > before + 0.1)
    return True


def test_my_ball_from_the_model_editor_is_inserted_and_seen_as_the_white_ball(open_page, studio_world,
                                                                             home, tmp_path):
    page = open_page()
    inspector = model_my_ball(page)
    screenshot(page, 'studio_model_editor.png', tmp_path)
    inspector.get_by_role('tab', name='Collision').click()
    expect(inspector.get_by_role('spinbutton', name='Radius')).to_have_value('0.1')
    expect(save_as(page, 'my_ball')).to_have_count(0)
    folder = home / '.gazebo' / 'models' / 'my_ball'
    assert sorted(os.listdir(folder)) == ['model.config', 'model.sdf']
    # Exit puts the model into this world, as Gazebo's editor does; the course's world is
    # another one, so it goes again here.
    choose(page, 'File', 'Exit Model Editor')
    wait_for(lambda: 'my_ball' in studio_world.model_names())
    page.get_by_role('list', name='Models').get_by_role('button', name='my_ball').click()
    page.locator('#view').focus()
    page.keyboard.press('Delete')
    wait_for(lambda: 'my_ball' not in studio_world.model_names())

    # Insert > my_ball, dropped in front of the robot's camera.
    page.get_by_role('tab', name='Insert').click()
    models = page.get_by_role('list', name=str(home / '.gazebo' / 'models'))
    models.get_by_role('button', name='my_ball').click()
    expect(page.get_by_role('status', name='Placing')).to_contain_text('place my_ball')
    drop(page, *BALL_AT)
    wait_for(lambda: 'my_ball' in studio_world.model_names())
    screenshot(page, 'studio_insert.png', tmp_path)
    where = position(studio_world, 'my_ball')
    assert (where['x'], where['y'], where['z']) == pytest.approx(BALL_AT + (0.0,), abs=0.05)
    assert studio_world.param('/flatsim/ball_names') == ['my_ball']
    # Pure white in the robot's camera: the course's detector finds it.
    image = studio_world.message('/camera/rgb/image_raw', 'sensor_msgs/Image')
    pixels = np.frombuffer(image['data'], np.uint8).reshape(image['height'], image['width'], 3)
    white = np.argwhere((pixels == 255).all(axis=2))
    assert len(white) > 100
    assert abs(white[:, 1].mean() - image['width'] / 2) < image['width'] / 20
    assert page.errors == []


def test_a_house_drawn_with_the_mouse_is_seen_by_the_lidar(open_page, studio_world, home, tmp_path):
    page = open_page()
    page.keyboard.press('Control+b')
    editor = page.get_by_role('region', name='Building Editor')
    editor.get_by_role('button', name='Wall').click()

    def click(x, y):
        point = page.evaluate('([x, y]) => window.studio.buildingEditor.screenPoint(x, y)', [x, y])
        page.mouse.click(point['x'], point['y'])

    for corner in CORNERS:
        click(*corner)
    # Back where it started: the chain is closed.
    expect(editor.get_by_role('status', name='Building Editor hint')).to_have_text('Click where the wall starts')
    page.keyboard.press('Escape')
    editor.get_by_role('button', name='Door').click()
    click(*DOOR_AT)
    door = editor.get_by_role('group', name='Door Inspector')
    offset = float(door.get_by_role('spinbutton', name='Position').input_value())
    assert offset == pytest.approx(DOOR_AT[1] - CORNERS[1][1], abs=0.03)
    screenshot(page, 'studio_building_editor.png', tmp_path)
    expect(save_as(page, 'house')).to_have_count(0)
    assert sorted(os.listdir(home / 'building_editor_models' / 'house')) == ['model.config', 'model.sdf']
    choose(page, 'File', 'Exit Building Editor')
    wait_for(lambda: 'house' in studio_world.model_names())
    centre = position(studio_world, 'house')
    assert (centre['x'], centre['y']) == pytest.approx((-2.0, 0.0))

    page.get_by_role('button', name='View', exact=True).click()
    page.get_by_role('menuitemcheckbox', name='Lidar Rays').click()
    page.evaluate("() => window.studio.connection.on('scans', (m) => { window.lastScans = m.scans; })")
    origin = wait_for(lambda: page.evaluate(
        '() => window.lastScans && window.lastScans.length ? window.lastScans[0].origin : null'))
    sensor_x, sensor_y, _, yaw = origin
    assert yaw == pytest.approx(0.0, abs=1e-3)
    scan = studio_world.message('/scan', 'sensor_msgs/LaserScan')

    def range_at(angle):
        value = scan['ranges'][round((angle - scan['angle_min']) / scan['angle_increment'])]
        return value if math.isfinite(value) else math.inf

    assert range_at(0.0) == pytest.approx(EAST_X - HALF_THICKNESS - sensor_x, abs=LIDAR_NOISE)
    assert range_at(math.pi / 2 - 1e-3) == pytest.approx(NORTH_Y - HALF_THICKNESS - sensor_y,
                                                         abs=LIDAR_NOISE)
    through_door = math.atan2(DOOR_AT[1] - sensor_y, DOOR_AT[0] - sensor_x)
    to_the_wall = (EAST_X - sensor_x) / math.cos(through_door)
    assert range_at(through_door) > to_the_wall + 1.0
    assert page.errors == []


def test_save_world_as_writes_the_world_without_the_robot_and_it_reloads(open_page, studio_world, home):
    page = open_page()
    choose(page, 'File', 'Save World As')
    dialog = page.get_by_role('dialog', name='Save World')
    dialog.get_by_role('button', name='Browse').click()
    chooser = page.get_by_role('dialog', name='Open Directory')
    expect(chooser.get_by_role('status', name='Folder')).to_have_text(str(home))
    chooser.get_by_role('list', name='Folders').get_by_role('button', name='worlds').click()
    expect(chooser.get_by_role('status', name='Folder')).to_have_text(str(home / 'worlds'))
    chooser.get_by_role('button', name='Choose').click()
    expect(chooser).to_have_count(0)
    # A name that is no world file is refused in the page, with what to type instead.
    dialog.get_by_role('textbox', name='File name:').fill('editors.txt')
    dialog.get_by_role('button', name='Save', exact=True).click()
    expect(page.get_by_role('alert')).to_contain_text(
        "the world file name 'editors.txt' must end in .world, such as myworld.world")
    dialog.get_by_role('textbox', name='File name:').fill('editors.world')
    dialog.get_by_role('button', name='Save', exact=True).click()
    expect(dialog).to_have_count(0)
    saved = home / 'worlds' / 'editors.world'
    messages = page.get_by_role('status', name='Messages')
    expect(messages).to_contain_text('Saved the world in %s' % saved)
    expect(messages).to_contain_text('my_robot is a robot spawned from URDF (the launch file spawns '
                                     'it); left out of the world')

    def models_in(path):
        return {model.name: model.pose for model in load_world(str(path)).models}

    in_file = models_in(saved)
    assert set(in_file) == {'ground_plane', 'my_ball', 'house'}
    for name in ('my_ball', 'house'):
        now = position(studio_world, name)
        assert (in_file[name].x, in_file[name].y) == pytest.approx((now['x'], now['y']), abs=1e-6)
    # Save World (Ctrl+S) now writes over that file, with the ball where it is now.
    studio_world.call('/gazebo/set_model_state', 'gazebo_msgs/SetModelState', {'model_state': {
        'model_name': 'my_ball', 'pose': {'position': {'x': 1.0, 'y': -2.0, 'z': 0.0}}}})
    page.locator('#view').focus()
    page.keyboard.press('Control+s')
    wait_for(lambda: models_in(saved)['my_ball'].y == pytest.approx(-2.0, abs=1e-3))
    assert page.errors == []


def test_the_insert_tab_lists_a_broken_model_and_says_why_it_cannot_go_in(open_page, studio_world, home):
    page = open_page()
    page.get_by_role('tab', name='Insert').click()
    broken = home / '.gazebo' / 'models' / 'broken'
    listed = page.get_by_role('list', name=str(broken.parent)).get_by_role('button', name='broken')
    expect(listed).to_contain_text('cannot be inserted: model.config cannot be read')
    listed.click()
    says = 'cannot insert broken (%s): model.config cannot be read' % broken
    expect(page.get_by_role('alert')).to_contain_text(says)
    assert says in log(studio_world)
    assert stepping(studio_world)


def test_bad_names_are_refused_with_a_clear_message_and_nothing_is_written(open_page, studio_world, home):
    page = open_page()
    choose(page, 'Edit', 'Model Editor')
    page.get_by_role('region', name='Model Editor').get_by_role('button', name='Box').click()
    for name in ('../escape', 'a/b'):
        dialog = save_as(page, name)
        says = "the model name %r may not hold '/'" % name
        expect(page.get_by_role('alert')).to_contain_text(says)
        assert says in log(studio_world)
        # The dialog stays, with what was typed, and the model is still being edited.
        expect(dialog.get_by_role('textbox', name='Model Name:')).to_have_value(name)
        dialog.get_by_role('button', name='Cancel').click()
    expect(page.get_by_role('list', name='Links').get_by_role('button')).to_have_count(1)
    assert not (home / 'escape').exists() and not (home / '.gazebo' / 'models' / 'a').exists()
    choose(page, 'File', 'Exit Model Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    choose(page, 'File', 'Save World As')
    dialog = page.get_by_role('dialog', name='Save World')
    dialog.get_by_role('button', name='Browse').click()
    chooser = page.get_by_role('dialog', name='Open Directory')
    chooser.get_by_role('button', name='Choose').click()
    expect(chooser).to_have_count(0)
    dialog.get_by_role('textbox', name='File name:').fill('../escape.world')
    dialog.get_by_role('button', name='Save', exact=True).click()
    says = "the world file name '../escape.world' may not hold '/'"
    expect(page.get_by_role('alert')).to_contain_text(says)
    assert says in log(studio_world)
    assert not (home.parent / 'escape.world').exists()
    assert stepping(studio_world)


def test_a_zero_length_wall_and_a_negative_size_are_refused_and_nothing_is_lost(open_page, studio_world,
                                                                               home):
    page = open_page()
    choose(page, 'Edit', 'Building Editor')
    editor = page.get_by_role('region', name='Building Editor')
    editor.get_by_role('button', name='Wall').click()
    for x, y in ((-6.0, 3.0), (-4.0, 3.0)):
        point = page.evaluate('([x, y]) => window.studio.buildingEditor.screenPoint(x, y)', [x, y])
        page.mouse.click(point['x'], point['y'])
    page.keyboard.press('Escape')
    point = page.evaluate('([x, y]) => window.studio.buildingEditor.screenPoint(x, y)', [-5.0, 3.0])
    page.mouse.click(point['x'], point['y'])
    wall = editor.get_by_role('group', name='Wall Inspector')
    fill(wall, 'spinbutton', 'End X', '-6')
    for says in ('Wall_0 has no length: it starts and ends at (-6.0, 3.0)',
                 'Wall_0 thickness must be a positive number, got -0.2'):
        dialog = save_as(page, 'shed')
        expect(page.get_by_role('alert')).to_contain_text(says)
        assert says in log(studio_world)
        dialog.get_by_role('button', name='Cancel').click()
        fill(wall, 'spinbutton', 'End X', '-4')
        fill(wall, 'spinbutton', 'Thickness', '-0.2')
    assert not (home / 'building_editor_models' / 'shed').exists()
    # Nothing lost: the wall is there as drawn, and saves once its thickness is put right.
    assert page.evaluate('() => window.studio.buildingEditor.design.walls.length') == 1
    fill(wall, 'spinbutton', 'Thickness', '0.2')
    expect(save_as(page, 'shed')).to_have_count(0)
    assert (home / 'building_editor_models' / 'shed' / 'model.sdf').exists()
    assert stepping(studio_world)
    choose(page, 'File', 'Exit Building Editor')
    wait_for(lambda: 'shed' in studio_world.model_names())


def test_two_tabs_saving_one_model_the_second_is_told_which_holds_it(open_page, studio_world, home):
    first, second = open_page(), open_page()
    for page, shape in ((first, 'Box'), (second, 'Cylinder')):
        choose(page, 'Edit', 'Model Editor')
        page.get_by_role('region', name='Model Editor').get_by_role('button', name=shape).click()
    expect(save_as(first, 'crate')).to_have_count(0)
    folder = home / '.gazebo' / 'models' / 'crate'
    written = (folder / 'model.sdf').read_text()
    dialog = save_as(second, 'crate')
    holder = first.evaluate('() => window.studio.session')
    says = '%s is being edited in the Model Editor of window %d' % (folder, holder)
    expect(second.get_by_role('alert')).to_contain_text(says)
    dialog.get_by_role('button', name='Cancel').click()
    assert (folder / 'model.sdf').read_text() == written
    # Once the first has done with it, the second may save over it, after saying so.
    choose(first, 'File', 'Exit Model Editor')
    wait_for(lambda: 'crate' in studio_world.model_names())
    save_as(second, 'crate')
    second.get_by_role('dialog', name='Files Exist').get_by_role('button', name='Save').click()
    wait_for(lambda: '<cylinder>' in (folder / 'model.sdf').read_text())
