"""Gazebo's hands in the studio, in a real browser, on the project's robot in the course's
empty world (`roslaunch my_robot world.launch gui:=false world_file:=.../empty.world x:=-2`):
the mouse in the 3D view as Gazebo's, the Scale tool, the right-click menu on a model, the
pose fields flatsim does not apply, and the walls' names in the Building Editor."""
import math

import pytest
from playwright.sync_api import expect

from studio_browser import (browser_context, choose, drop, fill,  # noqa: F401
                            open_page, save_as, start_empty_world, wait_for)

ROBOT = 'my_robot'
LIDAR_NOISE = 0.03               # 3 standard deviations of my_robot's laser noise, m
# A drag in the view, in pixels.
DRAG = 120


@pytest.fixture(scope='module')
def home(tmp_path_factory):
    return tmp_path_factory.mktemp('home')


@pytest.fixture(scope='module')
def studio_world(tmp_path_factory, home):
    with start_empty_world(tmp_path_factory.mktemp('studio'), home) as world:
        yield world


def camera(page):
    """Where the view's camera is and what it orbits about: (position, target)."""
    return page.evaluate('''() => {
        const view = window.studio.view;
        return [view.camera.position.toArray(), view.orbit.target.toArray()]; }''')


def direction(position, target):
    offset = [p - t for p, t in zip(position, target)]
    length = math.sqrt(sum(v * v for v in offset))
    return [v / length for v in offset], length


def empty_spot(page):
    """A point in the view with no model under it (the floor far from the robot), on screen."""
    box = page.locator('#view').bounding_box()
    for fx, fy in ((0.5, 0.75), (0.3, 0.7), (0.7, 0.7), (0.5, 0.6)):
        x, y = box['x'] + fx * box['width'], box['y'] + fy * box['height']
        if page.evaluate('([x, y]) => window.studio.view.modelAt(x, y)', [x, y]) is None:
            return x, y
    raise AssertionError('no empty spot in the view')


def mouse_drag(page, button='left', shift=False, dx=DRAG, dy=0):
    x, y = empty_spot(page)
    page.mouse.move(x, y)
    if shift:
        page.keyboard.down('Shift')
    page.mouse.down(button=button)
    for step in range(1, 11):
        page.mouse.move(x + dx * step / 10, y + dy * step / 10)
    page.mouse.up(button=button)
    if shift:
        page.keyboard.up('Shift')


def test_a_left_drag_pans_a_middle_or_shift_drag_orbits_and_a_right_drag_or_the_wheel_zooms(open_page):
    page = open_page()
    start_position, start_target = camera(page)
    start_direction, start_distance = direction(start_position, start_target)

    # Left drag: the view slides, looking the same way from as far.
    mouse_drag(page, 'left')
    position, target = camera(page)
    looking, distance = direction(position, target)
    assert math.dist(target, start_target) > 0.2
    assert looking == pytest.approx(start_direction, abs=1e-3)
    assert distance == pytest.approx(start_distance, rel=1e-3)

    # Middle drag, and Shift with a left drag: the view turns about the same point.
    for button, shift in (('middle', False), ('left', True)):
        before_position, before_target = camera(page)
        before_direction, before_distance = direction(before_position, before_target)
        mouse_drag(page, button, shift)
        position, target = camera(page)
        looking, distance = direction(position, target)
        assert target == pytest.approx(before_target, abs=1e-6), button
        assert math.dist(looking, before_direction) > 0.1, button
        assert distance == pytest.approx(before_distance, rel=1e-3), button

    # Right drag, and the wheel: nearer or further along the same line of sight.
    for zoom in ('right drag', 'wheel'):
        before_position, before_target = camera(page)
        before_direction, before_distance = direction(before_position, before_target)
        if zoom == 'wheel':
            x, y = empty_spot(page)
            page.mouse.move(x, y)
            page.mouse.wheel(0, 400)
        else:
            mouse_drag(page, 'right', dx=0, dy=DRAG)
        position, target = wait_for(lambda: (lambda found: found if direction(*found)[1] != pytest.approx(
            before_distance, rel=1e-3) else None)(camera(page)), timeout=5)
        looking, distance = direction(position, target)
        assert target == pytest.approx(before_target, abs=1e-6), zoom
        assert looking == pytest.approx(before_direction, abs=1e-3), zoom
        assert abs(distance - before_distance) > 0.03 * before_distance, zoom
    # No right-click menu came up for a drag.
    expect(page.get_by_role('menu', name='Model')).to_have_count(0)
    assert page.errors == []


def test_the_pose_fields_flatsim_does_not_apply_are_shown_as_not_applied(open_page, studio_world):
    page = open_page()
    page.get_by_role('button', name=ROBOT, exact=True).click()
    pose = page.get_by_role('group', name=ROBOT + ' pose')
    for field in ('z', 'roll', 'pitch'):
        entry = pose.get_by_role('spinbutton', name=field, exact=True)
        expect(entry).to_be_disabled()
        assert 'flatsim is 2D' in entry.get_attribute('title')
        expect(entry).to_have_accessible_description(
            'flatsim is 2D: a moving model stands on the ground and turns about z only, so its z, '
            'roll and pitch are not applied')
    expect(pose).to_contain_text('flatsim is 2D')
    # What it does apply still moves it.
    fill(pose, 'spinbutton', 'y', '0.5')
    wait_for(lambda: studio_world.model_state(ROBOT)['pose']['position']['y'] == pytest.approx(0.5, abs=0.01))

    # A static model takes its whole pose, as in Gazebo: nothing there is disabled.
    page.get_by_role('button', name='Box', exact=True).first.click()
    drop(page, 3.0, 3.0)
    box_name = wait_for(lambda: next((name for name in studio_world.model_names()
                                      if name.startswith('unit_box_')), None))
    page.get_by_role('button', name=box_name, exact=True).click()
    box_pose = page.get_by_role('group', name=box_name + ' pose')
    # The toolbar's box is dynamic: it moves, so it too stands on the ground.
    expect(box_pose.get_by_role('spinbutton', name='z', exact=True)).to_be_disabled()
    expect(box_pose.get_by_role('spinbutton', name='x', exact=True)).to_be_enabled()
    studio_world.call('/gazebo/delete_model', 'gazebo_msgs/DeleteModel', {'model_name': box_name})
    assert page.errors == []


def test_the_building_editor_shows_the_names_its_refusals_use(open_page, studio_world):
    page = open_page()
    choose(page, 'Edit', 'Building Editor')
    editor = page.get_by_role('region', name='Building Editor')
    editor.get_by_role('button', name='Wall').click()

    def screen(x, y):
        return page.evaluate('([x, y]) => window.studio.buildingEditor.screenPoint(x, y)', [x, y])

    for x, y in ((4.0, 4.0), (6.0, 4.0), (6.0, 6.0)):
        point = screen(x, y)
        page.mouse.click(point['x'], point['y'])
    page.keyboard.press('Escape')
    # Each wall's name is drawn at its middle.
    labels = page.evaluate('() => window.studio.buildingEditor.wallLabels')
    assert [label['name'] for label in labels] == ['Wall_0', 'Wall_1']
    for label, middle in zip(labels, ((5.0, 4.0), (6.0, 5.0))):
        at = screen(*middle)
        canvas = page.locator('canvas.building-canvas').bounding_box()
        centre = (canvas['x'] + label['x'] + label['width'] / 2, canvas['y'] + label['y'] + label['height'] / 2)
        assert math.dist(centre, (at['x'], at['y'])) < 3
    # A refusal names Wall_1: its label leads to it, and its inspector says its name.
    point = screen(6.0, 5.0)
    page.mouse.click(point['x'], point['y'])
    wall = editor.get_by_role('group', name='Wall Inspector')
    fill(wall, 'spinbutton', 'Height', '-1')
    dialog = save_as(page, 'corner')
    expect(page.get_by_role('alert')).to_contain_text('Wall_1 height must be a positive number')
    dialog.get_by_role('button', name='Cancel').click()
    expect(wall.get_by_role('status', name='Name')).to_have_text('Wall_1')
    point = screen(5.0, 4.0)
    page.mouse.click(point['x'], point['y'])
    expect(wall.get_by_role('status', name='Name')).to_have_text('Wall_0')
    choose(page, 'File', 'Exit Building Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    assert page.errors == []


def scan_range(world, angle=0.0):
    """The robot's lidar range along angle (rad, in its frame), from a fresh /scan."""
    scan = world.message('/scan', 'sensor_msgs/LaserScan')
    value = scan['ranges'][round((angle - scan['angle_min']) / scan['angle_increment'])]
    return value if math.isfinite(value) else math.inf


def shape_of(page, model):
    """The first shape of a model as the page's scene shows it."""
    return page.evaluate('''(name) => {
        const model = window.studio.scene.models.find((each) => each.name === name);
        return model ? model.links[0].shapes[0] : null; }''', model)


def test_the_scale_tool_stretches_a_box_into_a_wall_that_the_lidar_sees(open_page, studio_world):
    page = open_page()
    # The robot looks along +x; nothing is in front of it in the empty world.
    assert scan_range(studio_world) == math.inf
    # s on the robot: no handle, and a word saying why.
    page.get_by_role('button', name=ROBOT, exact=True).click()
    page.locator('#view').focus()
    page.keyboard.press('s')
    expect(page.get_by_role('button', name='Scale Mode')).to_have_attribute('aria-pressed', 'true')
    expect(page.get_by_role('status', name='Messages')).to_contain_text(
        'my_robot is not a simple shape: the Scale tool scales a box, a cylinder or a sphere')
    assert page.evaluate('() => window.studio.view.transform.object === undefined '
                         '|| window.studio.view.transform.object === null')

    # A box beside the robot's line of sight, stretched along y across it.
    page.get_by_role('button', name='Selection Mode').click()
    page.get_by_role('button', name='Box', exact=True).first.click()
    drop(page, 0.0, 1.2)
    box = wait_for(lambda: next((name for name in studio_world.model_names()
                                 if name.startswith('unit_box_')), None))
    wait_for(lambda: shape_of(page, box))
    assert scan_range(studio_world) == math.inf
    page.get_by_role('button', name=box, exact=True).click()
    page.get_by_role('button', name='Scale Mode').click()
    handle = wait_for(lambda: page.evaluate("() => window.studio.view.handlePoint('Y')"))
    centre = page.evaluate('''(name) => {
        const view = window.studio.view;
        return view.screenPointOf(view.models.get(name).group.position); }''', box)
    page.mouse.move(handle['x'], handle['y'])
    page.mouse.down()
    for step in range(1, 21):
        stretch = 1 + 3.0 * step / 20
        page.mouse.move(centre['x'] + stretch * (handle['x'] - centre['x']),
                        centre['y'] + stretch * (handle['y'] - centre['y']))
    page.mouse.up()
    # The simulator changed the box itself: the scene it sends says so.
    size = wait_for(lambda: (lambda shape: shape['size'] if shape and shape['size'][1] > 2.5 else None)(
        shape_of(page, box)))
    assert size[0] == pytest.approx(1.0) and size[2] == pytest.approx(1.0)
    state = studio_world.model_state(box)
    assert state['success']
    assert state['pose']['position']['x'] == pytest.approx(0.0, abs=0.01)
    # The lidar now meets its near face, across the robot's way.
    robot_x = page.evaluate('() => window.studio.poses.my_robot[0]')
    hokuyo = wait_for(lambda: scan_range(studio_world) if scan_range(studio_world) < math.inf else None)
    # (The lidar sits a little ahead of the robot's origin.)
    assert -0.5 - robot_x - 0.5 < hokuyo < -0.5 - robot_x + LIDAR_NOISE

    # A scale is one step for Edit > Undo: the simulator's box is a unit box again, out of the
    # lidar's way, and Redo stretches it across it once more.
    page.get_by_role('button', name='Edit', exact=True).click()
    expect(page.get_by_role('menu', name='Edit').get_by_role('menuitem', name='Undo', exact=True)) \
        .to_have_attribute('title', 'Undo Scale %s' % box)
    page.get_by_role('button', name='Edit', exact=True).click()
    page.keyboard.press('Control+z')
    wait_for(lambda: scan_range(studio_world) == math.inf)
    wait_for(lambda: (shape_of(page, box) or {}).get('size') == pytest.approx([1.0, 1.0, 1.0]))
    assert box in studio_world.model_names()
    page.keyboard.press('Control+Shift+Z')
    wait_for(lambda: scan_range(studio_world) < math.inf)
    wait_for(lambda: (shape_of(page, box) or {}).get('size') == pytest.approx(size))
    studio_world.call('/gazebo/delete_model', 'gazebo_msgs/DeleteModel', {'model_name': box})
    page.get_by_role('button', name='Selection Mode').click()
    assert page.errors == []


def screen_point_of(page, model):
    """Where the middle of the model's shapes is on the screen."""
    return page.evaluate('(name) => window.studio.view.modelPoint(name)', model)


def right_click(page, model):
    point = screen_point_of(page, model)
    page.mouse.click(point['x'], point['y'], button='right')
    menu = page.get_by_role('menu', name='Model')
    expect(menu).to_be_visible()
    # The menu is for the model clicked, which the click selected, as Gazebo's does.
    assert page.evaluate('() => window.studio.selected') == model
    return menu


def orbit_target(page):
    return page.evaluate('() => window.studio.view.orbit.target.toArray()')


def looks(page, model):
    """How the page draws the model's own meshes, and its collision shapes."""
    return page.evaluate('''(name) => {
        const found = {transparent: [], wireframe: [], collisions: 0};
        window.studio.view.models.get(name).group.traverse((object) => {
            if (!object.isMesh) return;
            let shown = object.visible;
            for (let up = object.parent; up; up = up.parent) shown = shown && up.visible;
            if (object.userData.collision) { if (shown) found.collisions += 1; return; }
            found.transparent.push(object.material.transparent && object.material.opacity <= 0.5);
            found.wireframe.push(object.material.wireframe);
        });
        return found; }''', model)


def insert_box(page, world, at):
    before = set(world.model_names())
    page.get_by_role('button', name='Box', exact=True).first.click()
    drop(page, *at)
    name = wait_for(lambda: next((name for name in world.model_names()
                                  if name.startswith('unit_box_') and name not in before), None))
    wait_for(lambda: page.evaluate('(name) => window.studio.view.models.has(name)', name))
    return name


def set_position(world, model, x, y):
    state = world.model_state(model)
    reply = world.call('/gazebo/set_model_state', 'gazebo_msgs/SetModelState', {'model_state': {
        'model_name': model, 'pose': {'position': {'x': x, 'y': y, 'z': state['pose']['position']['z']},
                                      'orientation': {'w': 1.0}}}})
    assert reply['success'], reply['status_message']


def test_the_right_click_menu_has_gazebos_entries_and_each_works(open_page, studio_world):
    page = open_page()
    box = insert_box(page, studio_world, (1.5, 1.5))
    menu = right_click(page, box)
    entries = menu.get_by_role('menuitem')
    expect(entries).to_have_text(['Move To', 'Follow', 'Edit model', 'View', 'Copy', 'Paste', 'Delete'])

    # Move To: the camera turns to the model.
    menu.get_by_role('menuitem', name='Move To').click()
    expect(menu).to_be_hidden()
    # (The box's one shape sits at its origin.)
    centre = page.evaluate('(name) => window.studio.view.models.get(name).group.position.toArray()', box)
    assert math.dist(orbit_target(page), centre) < 0.05

    # Follow: the camera goes where the model goes; Esc stops it.
    right_click(page, box).get_by_role('menuitem', name='Follow').click()
    start = orbit_target(page)
    set_position(studio_world, box, 2.5, 1.5)
    wait_for(lambda: orbit_target(page)[0] == pytest.approx(start[0] + 1.0, abs=0.02))
    assert orbit_target(page)[1] == pytest.approx(start[1], abs=0.02)
    page.evaluate("() => window.studio.run('setMode', 'translate')")
    page.locator('#view').focus()
    page.keyboard.press('Escape')
    followed = orbit_target(page)
    # (Esc stopped following and, as Gazebo's, went back to the selection mode.)
    assert page.evaluate('() => window.studio.view.mode') == 'select'
    set_position(studio_world, box, 2.5, 2.5)
    wait_for(lambda: page.evaluate('(name) => window.studio.poses[name][1]', box) == pytest.approx(2.5, abs=0.01))
    assert orbit_target(page) == pytest.approx(followed, abs=1e-6)

    # View > Transparent, Wireframe, Collisions: each on its own, checked in the menu after.
    assert looks(page, box) == {'transparent': [False], 'wireframe': [False], 'collisions': 0}
    for entry, expected in (('Transparent', {'transparent': [True], 'wireframe': [False], 'collisions': 0}),
                            ('Wireframe', {'transparent': [True], 'wireframe': [True], 'collisions': 0}),
                            ('Collisions', {'transparent': [True], 'wireframe': [True], 'collisions': 1})):
        right_click(page, box).get_by_role('menuitem', name='View').click()
        page.get_by_role('menu', name='View').get_by_role('menuitemcheckbox', name=entry).click()
        assert looks(page, box) == expected, entry
        right_click(page, box).get_by_role('menuitem', name='View').click()
        expect(page.get_by_role('menu', name='View').get_by_role('menuitemcheckbox', name=entry)) \
            .to_have_attribute('aria-checked', 'true')
        # Esc with the menu open closes it, and is nothing else: the tool in hand stays.
        page.evaluate("() => window.studio.run('setMode', 'translate')")
        page.keyboard.press('Escape')
        expect(page.get_by_role('menu', name='Model')).to_be_hidden()
        assert page.evaluate('() => window.studio.view.mode') == 'translate'
        page.evaluate("() => window.studio.run('setMode', 'select')")
    right_click(page, box).get_by_role('menuitem', name='View').click()
    page.get_by_role('menu', name='View').get_by_role('menuitemcheckbox', name='Transparent').click()
    assert looks(page, box)['transparent'] == [False]

    # Edit model: the Model Editor opens with the model's shape; saved and exited, the edited
    # model takes its place in the world.
    right_click(page, box).get_by_role('menuitem', name='Edit model').click()
    editor = page.get_by_role('region', name='Model Editor')
    expect(editor).to_be_visible()
    expect(editor.get_by_role('textbox', name='Model name')).to_have_value(box)
    expect(editor.get_by_role('list', name='Links').get_by_role('button')).to_have_count(1)
    inspector = editor.get_by_role('group', name='Link Inspector')
    inspector.get_by_role('tab', name='Visual').click()
    expect(inspector.get_by_role('spinbutton', name='Y')).to_have_value('1')
    fill(inspector, 'spinbutton', 'Y', '2')
    expect(save_as(page, 'long_box')).to_have_count(0)
    choose(page, 'File', 'Exit Model Editor')
    wait_for(lambda: 'long_box' in studio_world.model_names() and box not in studio_world.model_names())
    edited = studio_world.model_state('long_box')['pose']['position']
    assert (edited['x'], edited['y']) == pytest.approx((2.5, 2.5), abs=0.01)
    wait_for(lambda: page.evaluate('() => window.studio.view.models.has("long_box")'))
    assert shape_of(page, 'long_box')['size'] == pytest.approx([1.0, 2.0, 1.0])

    # A robot's sensors and plugins would not come back from the editor: it says so instead.
    page.evaluate('(name) => window.studio.view.moveTo(name)', ROBOT)
    right_click(page, ROBOT).get_by_role('menuitem', name='Edit model').click()
    expect(page.get_by_role('alert')).to_contain_text(
        'my_robot is a robot from its URDF: edit its xacro, not its shapes here')
    expect(page.get_by_role('region', name='Model Editor')).to_be_hidden()

    # Copy and Paste, as the Edit menu's: Gazebo's NAME_clone beside it.
    right_click(page, 'long_box').get_by_role('menuitem', name='Copy').click()
    right_click(page, 'long_box').get_by_role('menuitem', name='Paste').click()
    wait_for(lambda: 'long_box_clone' in studio_world.model_names())
    # Apart, so that neither hides the other from the view.
    set_position(studio_world, 'long_box_clone', 0.5, 3.5)
    wait_for(lambda: (page.evaluate("() => window.studio.poses.long_box_clone || [0, 0]")[:2]
                      == pytest.approx([0.5, 3.5], abs=0.01)))

    # Delete: through the simulator, as the Edit menu's.
    for name in ('long_box_clone', 'long_box'):
        wait_for(lambda: page.evaluate('(name) => window.studio.view.models.has(name)', name))
        right_click(page, name).get_by_role('menuitem', name='Delete').click()
        wait_for(lambda: name not in studio_world.model_names())
    assert page.errors == []


def test_the_model_editors_specular_says_flatsims_camera_does_not_use_it(open_page):
    page = open_page()
    choose(page, 'Edit', 'Model Editor')
    editor = page.get_by_role('region', name='Model Editor')
    editor.get_by_role('group', name='Simple Shapes').get_by_role('button', name='Sphere').click()
    inspector = editor.get_by_role('group', name='Link Inspector')
    inspector.get_by_role('tab', name='Visual').click()
    assert "not used by flatsim's camera" in inspector.get_by_role('textbox', name='Specular').get_attribute('title')
    for colour in ('Ambient', 'Diffuse', 'Emissive'):
        assert 'flatsim' not in inspector.get_by_role('textbox', name=colour).get_attribute('title')
    choose(page, 'File', 'Exit Model Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    assert page.errors == []
