"""A student's first steps in the studio, in a real browser, from a fresh home folder (no
~/.gazebo yet), on the project's robot in the course's empty world
(`roslaunch my_robot world.launch gui:=false world_file:=.../empty.world x:=-2`): the first
view, the folder chooser, the messages over the view, a new shape in the Model Editor, and
the small things around them."""

import cv2
import numpy as np
import pytest
from playwright.sync_api import expect

from studio_browser import (browser_context, choose, fill, floor_point_on_screen, open_page,  # noqa: F401
                            page_pose, save_as, start_empty_world, wait_for)

# empty.world's <gui><camera><pose>.
GUI_CAMERA = (-3.0, -3.0, 2.5, 0.0, 0.5, 0.785398)


@pytest.fixture(scope='module')
def home(tmp_path_factory):
    return tmp_path_factory.mktemp('home')


@pytest.fixture(scope='module')
def studio_world(tmp_path_factory, home):
    with start_empty_world(tmp_path_factory.mktemp('studio'), home) as world:
        yield world


def position(world, model):
    state = world.model_state(model)
    assert state['success'], state['status_message']
    return state['pose']['position']


def view_pixels(page):
    """The 3D view as drawn now: (rgb pixels, its top left corner on the page)."""
    canvas = page.locator('#view')
    shot = cv2.imdecode(np.frombuffer(canvas.screenshot(), np.uint8), cv2.IMREAD_COLOR)
    box = canvas.bounding_box()
    return shot[:, :, ::-1].astype(int), (box['x'], box['y'])


def overlap(a, b):
    return (a['x'] < b['x'] + b['width'] and b['x'] < a['x'] + a['width']
            and a['y'] < b['y'] + b['height'] and b['y'] < a['y'] + a['height'])


def test_save_as_browse_in_a_fresh_home_opens_the_model_folder_with_home_new_folder_and_worlds(
        open_page, studio_world, home):
    assert not (home / '.gazebo').exists()
    (home / 'mine.world').write_text('<sdf version="1.6"><world name="default"/></sdf>')
    page = open_page()
    choose(page, 'Edit', 'Model Editor')
    page.get_by_role('region', name='Model Editor').get_by_role('button', name='Box').click()
    choose(page, 'File', 'Save As')
    dialog = page.get_by_role('dialog', name='Save Model')
    dialog.get_by_role('button', name='Browse').click()
    chooser = page.get_by_role('dialog', name='Open Directory')
    # Made, as Gazebo makes it when it starts, and opened without a word of refusal.
    expect(chooser.get_by_role('status', name='Folder')).to_have_text(str(home / '.gazebo' / 'models'))
    assert (home / '.gazebo' / 'models').is_dir()
    expect(page.locator('#alerts p')).to_have_count(0)
    chooser.get_by_role('button', name='Home').click()
    expect(chooser.get_by_role('status', name='Folder')).to_have_text(str(home))
    listed = chooser.get_by_role('list', name='Folders')
    # The worlds there are seen, but are no folder to open.
    expect(listed.get_by_role('listitem').filter(has_text='mine.world')).to_have_count(1)
    expect(listed.get_by_role('button', name='mine.world')).to_have_count(0)
    expect(listed.get_by_role('button', name='.gazebo')).to_have_count(1)

    chooser.get_by_role('button', name='New Folder').click()
    naming = page.get_by_role('dialog', name='New Folder')
    naming.get_by_role('textbox', name='Folder name:').fill('a/b')
    naming.get_by_role('button', name='Create').click()
    expect(page.get_by_role('alert')).to_contain_text("a folder name holds no '/'")
    assert not (home / 'a').exists()
    naming.get_by_role('textbox', name='Folder name:').fill('worlds')
    naming.get_by_role('button', name='Create').click()
    expect(naming).to_have_count(0)
    assert (home / 'worlds').is_dir()
    expect(chooser.get_by_role('status', name='Folder')).to_have_text(str(home / 'worlds'))
    chooser.get_by_role('button', name='Choose').click()
    expect(chooser).to_have_count(0)
    expect(dialog.get_by_role('textbox', name='Location:')).to_have_value(str(home / 'worlds'))
    dialog.get_by_role('button', name='Cancel').click()
    choose(page, 'File', 'Exit Model Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    assert page.errors == []


def test_the_first_view_looks_from_the_worlds_gui_camera_on_a_grid_under_a_sky(open_page):
    page = open_page()
    camera = page.evaluate('''() => { const view = window.studio.view, at = view.camera.position;
        const along = view.orbit.target.clone().sub(at).normalize();
        return {at: [at.x, at.y, at.z], along: [along.x, along.y, along.z]}; }''')
    x, y, z, _, pitch, yaw = GUI_CAMERA
    assert camera['at'] == pytest.approx([x, y, z], abs=1e-3)
    assert camera['along'] == pytest.approx([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw),
                                             -np.sin(pitch)], abs=1e-3)
    # The grid's lines near the origin, lighter than the floor between them.
    pixels, (left, top) = view_pixels(page)
    origin = floor_point_on_screen(page, 0.0, 0.0)
    col, row = int(origin['x'] - left), int(origin['y'] - top)
    patch = pixels[row - 60:row + 60, col - 60:col + 60].mean(axis=2)
    floor = np.median(patch)
    assert (patch > floor + 15).sum() > 100

    # Looking level, the sky: blue-grey overhead, lighter and greyer at the horizon.
    page.evaluate('() => window.studio.view.lookFrom([0, 0, 1, 0, 0, 0])')
    page.wait_for_timeout(200)
    pixels, _ = view_pixels(page)
    overhead, horizon = pixels[2, pixels.shape[1] // 2], pixels[pixels.shape[0] // 2 - 20, pixels.shape[1] // 2]
    assert overhead[2] - overhead[0] > 20
    assert abs(horizon[2] - horizon[0]) < abs(overhead[2] - overhead[0])
    assert horizon.sum() > overhead.sum()
    assert page.errors == []


def test_messages_let_a_drop_through_can_be_dismissed_and_alerts_stack_beside_them(open_page,
                                                                                  studio_world):
    page = open_page()
    page.evaluate("() => window.studio.inform('Saved the world in /a/rather/long/folder/name/"
                  "of/a/student/who/likes/long/names/my_world.world')")
    message = page.get_by_role('status', name='Messages').locator('p')
    expect(message).to_have_count(1)
    box = message.bounding_box()
    assert overlap(box, page.locator('#view').bounding_box())
    # A drop on the message goes to the floor under it.
    page.get_by_role('toolbar', name='Tools').get_by_role('button', name='Box').click()
    page.mouse.click(box['x'] + box['width'] / 2, box['y'] + box['height'] / 2)
    wait_for(lambda: 'unit_box_0' in studio_world.model_names())
    expect(page.get_by_role('status', name='Messages')).to_contain_text('Inserted unit_box_0')

    for index in range(5):
        page.evaluate('(n) => window.studio.notify("refused number " + n + ", which says a good deal '
                      'about why it was refused")', index)
    alerts = page.locator('#alerts p')
    expect(alerts).to_have_count(3)
    expect(alerts.first).to_contain_text('refused number 2')
    shown = [alerts.nth(i).bounding_box() for i in range(3)]
    shown += [message.nth(i).bounding_box() for i in range(message.count())]
    assert all(not overlap(a, b) for i, a in enumerate(shown) for b in shown[i + 1:])
    # Dismissed at once, without waiting.
    count = message.count()
    message.first.get_by_role('button', name='Dismiss').click()
    expect(message).to_have_count(count - 1)
    assert page.errors == []


def test_a_new_shape_in_the_model_editor_is_made_where_the_view_looks_and_framed(open_page, studio_world):
    page = open_page()
    page.evaluate('''() => { const view = window.studio.view;
        view.orbit.target.set(3, 2, 0); view.camera.position.set(-3, -8, 9); view.orbit.update(); }''')
    choose(page, 'Edit', 'Model Editor')
    page.get_by_role('region', name='Model Editor').get_by_role('button', name='Box').click()
    shown = page.evaluate('''() => { const view = window.studio.view;
        const preview = view.scene.getObjectByName('Model Editor: Untitled');
        const rect = view.canvas.getBoundingClientRect();
        const corners = [];
        for (const x of [-0.5, 0.5]) for (const y of [-0.5, 0.5]) for (const z of [0, 1]) {
          corners.push(view.screenPointOf(preview.position.clone().add({x, y, z})));
        }
        return {at: [preview.position.x, preview.position.y], corners,
                rect: {left: rect.left, top: rect.top, right: rect.right, bottom: rect.bottom}}; }''')
    assert shown['at'] == pytest.approx([3.0, 2.0], abs=1e-6)
    rect = shown['rect']
    xs = [corner['x'] for corner in shown['corners']]
    ys = [corner['y'] for corner in shown['corners']]
    assert rect['left'] < min(xs) and max(xs) < rect['right']
    assert rect['top'] < min(ys) and max(ys) < rect['bottom']
    # Framed: it takes a good part of the view, not a speck far off.
    assert max(ys) - min(ys) > (rect['bottom'] - rect['top']) / 6
    expect(save_as(page, 'crate')).to_have_count(0)
    choose(page, 'File', 'Exit Model Editor')
    wait_for(lambda: 'crate' in studio_world.model_names())
    where = position(studio_world, 'crate')
    assert (where['x'], where['y']) == pytest.approx((3.0, 2.0), abs=0.05)
    assert page.errors == []


def contrast(page, locator):
    """The contrast ratio (WCAG) of an element's text colour on its parent's background."""
    return locator.evaluate('''(element) => {
        const parse = (text) => text.match(/[\\d.]+/g).slice(0, 3).map(Number);
        const lum = (rgb) => { const [r, g, b] = rgb.map((c) => { c /= 255;
            return c <= 0.03928 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4; });
            return 0.2126 * r + 0.7152 * g + 0.0722 * b; };
        const text = lum(parse(getComputedStyle(element).color));
        const back = lum(parse(getComputedStyle(element.parentElement).backgroundColor));
        return (Math.max(text, back) + 0.05) / (Math.min(text, back) + 0.05); }''')


def test_a_refused_pose_is_put_back_and_a_note_on_the_selected_row_is_readable(open_page, studio_world):
    page, other = open_page(), open_page()
    models = page.get_by_role('list', name='Models')
    models.get_by_role('button', name='my_robot').click()
    pose = page.get_by_role('group', name='my_robot pose')
    fill(pose, 'spinbutton', 'x', '2000000')
    expect(page.get_by_role('alert')).to_contain_text('too far from the origin')
    expect(pose.get_by_role('spinbutton', name='x')).to_have_value('%.3f' % page_pose(page, 'my_robot')[0])

    # Another window keeps editing the robot: the selected row says so, readably.
    other.evaluate('''() => { const studio = window.studio;
        setInterval(() => studio.connection.request('set_pose', {model: 'my_robot',
                                                                 pose: studio.poses.my_robot}), 300); }''')
    row = models.get_by_role('button', name='my_robot')
    expect(row).to_contain_text('being edited in another window')
    assert contrast(page, row.locator('.editing')) >= 4.5
    other.close()


def test_the_building_editor_keeps_the_models_names_apart(open_page, studio_world):
    page = open_page()
    for at in ([-1.9, 0.05], [-1.8, -0.05]):
        assert page.evaluate('(at) => window.studio.request("insert", {shape: "sphere", at})'
                             '.then((reply) => reply.ok)', at)
    wait_for(lambda: {'unit_sphere_0', 'unit_sphere_1'} <= set(studio_world.model_names()))
    page.keyboard.press('Control+b')
    expect(page.get_by_role('region', name='Building Editor')).to_be_visible()
    labels = wait_for(lambda: page.evaluate('() => window.studio.buildingEditor.labels'))
    names = {label['name'] for label in labels}
    assert {'my_robot', 'unit_sphere_0', 'unit_sphere_1'} <= names
    assert all(not overlap(a, b) for i, a in enumerate(labels) for b in labels[i + 1:])
    choose(page, 'File', 'Exit Building Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    assert page.errors == []


def test_the_building_editor_shows_the_length_lets_shift_off_the_grid_and_asks_before_closing(
        open_page):
    page = open_page()
    page.keyboard.press('Control+b')
    editor = page.get_by_role('region', name='Building Editor')
    editor.get_by_role('button', name='Wall').click()
    hint = editor.get_by_role('status', name='Building Editor hint')

    def screen(x, y):
        return page.evaluate('([x, y]) => window.studio.buildingEditor.screenPoint(x, y)', [x, y])

    start = screen(5.0, 5.0)
    page.mouse.click(start['x'], start['y'])
    expect(hint).to_contain_text('click the first corner to close the loop')
    # While drawn, the wall's length: snapped to the grid, then with Shift where the mouse is.
    end = screen(7.1, 5.0)
    page.mouse.move(end['x'], end['y'])
    expect(hint).to_contain_text('this wall: 2 m')
    page.keyboard.down('Shift')
    end = screen(7.13, 5.0)
    page.mouse.move(end['x'] - 3, end['y'])
    page.mouse.move(end['x'], end['y'])
    expect(hint).not_to_contain_text('this wall: 2 m')
    expect(hint).to_contain_text('this wall: 2.1')
    page.mouse.click(end['x'], end['y'])
    page.keyboard.up('Shift')
    page.keyboard.press('Escape')
    walls = page.evaluate('() => window.studio.buildingEditor.design.walls')
    assert len(walls) == 1
    assert walls[0]['end'][0] == pytest.approx(7.13, abs=0.03)
    assert walls[0]['end'][0] not in (7.0, 7.25)

    middle = screen(6.0, 5.0)
    page.mouse.click(middle['x'], middle['y'])
    wall = editor.get_by_role('group', name='Wall Inspector')
    for field in ('Start X', 'End Y', 'Height', 'Thickness'):
        expect(wall.get_by_role('spinbutton', name=field).locator('xpath=..')).to_have_text('m')

    # The design is not saved: closing the tab asks first, and staying keeps it.
    asked = []

    def answer(dialog):
        asked.append(dialog.type)
        dialog.dismiss()
    page.on('dialog', answer)
    page.close(run_before_unload=True)
    for _ in range(100):
        # Playwright's events come while it waits, not while Python sleeps.
        if asked:
            break
        page.wait_for_timeout(100)
    assert asked == ['beforeunload']
    assert not page.is_closed()
    assert page.evaluate('() => window.studio.buildingEditor.design.walls.length') == 1
