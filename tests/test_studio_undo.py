"""Undo and Redo as Gazebo's window has them (Edit > Undo and Redo, Ctrl+Z, Ctrl+Shift+Z), in a
real browser on the project's world. Each goes through the simulator: the tests read its state
over ROS (/gazebo/get_world_properties, /gazebo/get_model_state), never only the page."""
import pytest
from playwright.sync_api import expect

from studio_browser import (browser_context, choose, drop, fill, open_page,  # noqa: F401
                            studio_world, wait_for)
from test_studio import grab_handle, select, set_field

# A free spot on the floor, outside the house.
OUTSIDE = (2.0, 5.5)


def position(world, model):
    state = world.model_state(model)
    assert state['success'], state['status_message']
    where = state['pose']['position']
    return where['x'], where['y'], where['z']


def put_ball(world, x, y):
    """Move the ball as a ROS node does, with /gazebo/set_model_state."""
    moved = world.call('/gazebo/set_model_state', 'gazebo_msgs/SetModelState', {'model_state': {
        'model_name': 'white_ball', 'pose': {'position': {'x': x, 'y': y, 'z': 0.1},
                                             'orientation': {'w': 1.0}}}})
    assert moved['success'], moved['status_message']


def models_list(page):
    return page.get_by_role('list', name='Models')


def edit_entry(page, label):
    return page.get_by_role('menu', name='Edit').get_by_role('menuitem', name=label, exact=True)


def test_an_insert_is_undone_in_the_simulation_and_redone_where_it_was_from_any_window(
        open_page, studio_world):
    page = open_page()
    # Gazebo's Edit menu: Undo and Redo first, greyed while there is nothing to do.
    page.get_by_role('button', name='Edit', exact=True).click()
    entries = page.get_by_role('menu', name='Edit').get_by_role('menuitem')
    expect(entries.nth(0)).to_have_attribute('aria-keyshortcuts', 'Ctrl+Z')
    expect(entries.nth(0)).to_contain_text('Undo')
    expect(entries.nth(1)).to_have_attribute('aria-keyshortcuts', 'Ctrl+Shift+Z')
    expect(edit_entry(page, 'Undo')).to_have_attribute('aria-disabled', 'true')
    page.get_by_role('button', name='Edit', exact=True).click()

    page.get_by_role('toolbar', name='Tools').get_by_role('button', name='Box').click()
    drop(page, *OUTSIDE)
    wait_for(lambda: 'unit_box_0' in studio_world.model_names())
    placed = position(studio_world, 'unit_box_0')
    page.get_by_role('button', name='Edit', exact=True).click()
    expect(edit_entry(page, 'Undo')).to_have_attribute('aria-disabled', 'false')
    expect(edit_entry(page, 'Undo')).to_have_attribute('title', 'Undo Insert unit_box_0')
    page.get_by_role('button', name='Edit', exact=True).click()

    page.keyboard.press('Control+z')
    wait_for(lambda: 'unit_box_0' not in studio_world.model_names())
    expect(models_list(page).get_by_role('button', name='unit_box_0')).to_have_count(0)
    page.keyboard.press('Control+Shift+Z')
    wait_for(lambda: 'unit_box_0' in studio_world.model_names())
    assert position(studio_world, 'unit_box_0') == pytest.approx(placed, abs=1e-3)
    expect(models_list(page).get_by_role('button', name='unit_box_0')).to_have_count(1)

    # One history for every window: another tab undoes it from its Edit menu.
    other = open_page()
    choose(other, 'Edit', 'Undo')
    wait_for(lambda: 'unit_box_0' not in studio_world.model_names())
    expect(models_list(page).get_by_role('button', name='unit_box_0')).to_have_count(0)
    assert page.errors == [] and other.errors == []


def test_a_delete_and_a_paste_are_undone_with_the_model_as_it_was(open_page, studio_world):
    page = open_page()
    before = position(studio_world, 'white_ball')
    select(page, 'white_ball')
    page.locator('#view').focus()
    page.keyboard.press('Delete')
    wait_for(lambda: 'white_ball' not in studio_world.model_names())
    page.keyboard.press('Control+z')
    wait_for(lambda: 'white_ball' in studio_world.model_names())
    assert position(studio_world, 'white_ball') == pytest.approx(before, abs=1e-3)
    # Made again from its SDF: still the white ball the robot chases.
    wait_for(lambda: page.evaluate('''() => { const model = window.studio.scene.models.find(
        (m) => m.name === 'white_ball'); return model && model.kind; }''') == 'ball')
    shapes = page.evaluate('''() => window.studio.scene.models.find((m) => m.name === 'white_ball')
        .links[0].shapes.map((s) => [s.shape, s.size])''')
    assert shapes == [['sphere', [0.1]]]

    # A pasted copy is taken back the same way.
    select(page, 'white_ball')
    page.locator('#view').focus()
    page.keyboard.press('Control+c')
    page.keyboard.press('Control+v')
    wait_for(lambda: 'white_ball_clone' in studio_world.model_names())
    page.keyboard.press('Control+z')
    wait_for(lambda: 'white_ball_clone' not in studio_world.model_names())
    assert page.errors == []


def test_a_move_with_the_translate_tool_or_a_pose_field_is_undone_in_the_simulation(
        open_page, studio_world):
    page = open_page()
    start = position(studio_world, 'white_ball')
    grab_handle(page, 'white_ball')
    page.mouse.up()
    # Once the page has let go of the ball, its drag is one Move in the history.
    wait_for(lambda: page.evaluate('() => window.studio.leases.white_ball === undefined'))
    assert position(studio_world, 'white_ball')[:2] != pytest.approx(start[:2], abs=0.05)
    dragged = position(studio_world, 'white_ball')
    page.keyboard.press('Escape')
    # The whole drag is one step back.
    page.keyboard.press('Control+z')
    wait_for(lambda: position(studio_world, 'white_ball') == pytest.approx(start, abs=1e-3))
    page.keyboard.press('Control+Shift+Z')
    wait_for(lambda: position(studio_world, 'white_ball') == pytest.approx(dragged, abs=1e-3))

    set_field(page, 'white_ball', 'y', 0.0)
    wait_for(lambda: position(studio_world, 'white_ball')[1] == pytest.approx(0.0, abs=1e-3))
    # Ctrl+Z in a field is the field's own; Edit > Undo is the world's.
    choose(page, 'Edit', 'Undo')
    wait_for(lambda: position(studio_world, 'white_ball') == pytest.approx(dragged, abs=1e-3))
    assert page.errors == []


def test_changes_from_outside_the_studio_never_make_undo_do_something_else(open_page, studio_world):
    page = open_page()
    put_ball(studio_world, 2.5, 0.5)
    start = position(studio_world, 'white_ball')
    set_field(page, 'white_ball', 'y', 0.0)
    wait_for(lambda: position(studio_world, 'white_ball')[1] == pytest.approx(0.0, abs=1e-3))
    assert page.evaluate('() => window.studio.history.undo[0]') == 'Move white_ball'
    page.get_by_role('toolbar', name='Tools').get_by_role('button', name='Cylinder').click()
    drop(page, *OUTSIDE)
    wait_for(lambda: 'unit_cylinder_0' in studio_world.model_names())
    # It is deleted with /gazebo/delete_model: Undo leaves it out, and says so.
    deleted = studio_world.call('/gazebo/delete_model', 'gazebo_msgs/DeleteModel',
                                {'model_name': 'unit_cylinder_0'})
    assert deleted['success']
    expect(page.get_by_role('status', name='Messages')).to_contain_text(
        'Undo leaves out unit_cylinder_0: changed outside the studio')
    # The ball is pushed on by a ROS node: Undo still puts it where it was before the edit.
    put_ball(studio_world, 1.0, 1.0)
    wait_for(lambda: page.evaluate('() => window.studio.history.undo[0]') == 'Move white_ball')
    page.keyboard.press('Control+z')
    wait_for(lambda: position(studio_world, 'white_ball') == pytest.approx(start, abs=1e-3))
    assert 'unit_cylinder_0' not in studio_world.model_names()
    assert page.errors == []


def test_the_model_editor_undoes_and_redoes_its_own_edits_and_never_the_worlds(open_page, studio_world):
    page = open_page()
    world_history = page.evaluate('() => window.studio.history.undo.length')
    names = set(studio_world.model_names())
    choose(page, 'Edit', 'Model Editor')
    editor = page.get_by_role('region', name='Model Editor')
    links = editor.get_by_role('list', name='Links')
    editor.get_by_role('group', name='Simple Shapes').get_by_role('button', name='Box').click()
    expect(links.get_by_role('button', name='link_0')).to_have_count(1)
    preview = "() => !!window.studio.view.scene.getObjectByName('Model Editor: Untitled')"
    assert page.evaluate(preview)
    page.keyboard.press('Control+z')
    expect(links.get_by_role('button')).to_have_count(0)
    assert not page.evaluate(preview)
    page.keyboard.press('Control+Shift+Z')
    expect(links.get_by_role('button', name='link_0')).to_have_count(1)
    assert page.evaluate(preview)

    inspector = editor.get_by_role('group', name='Link Inspector')
    inspector.get_by_role('tab', name='Visual').click()
    fill(inspector, 'spinbutton', 'X', '2.5')
    fill(inspector, 'textbox', 'Diffuse', '1 0 0 1')
    choose(page, 'Edit', 'Undo')
    inspector.get_by_role('tab', name='Visual').click()
    expect(inspector.get_by_role('textbox', name='Diffuse')).to_have_value('0.7 0.7 0.7 1')
    expect(inspector.get_by_role('spinbutton', name='X')).to_have_value('2.5')
    choose(page, 'Edit', 'Undo')
    expect(inspector.get_by_role('spinbutton', name='X')).to_have_value('1')
    choose(page, 'Edit', 'Redo')
    expect(inspector.get_by_role('spinbutton', name='X')).to_have_value('2.5')

    # The world was not touched.
    assert page.evaluate('() => window.studio.history.undo.length') == world_history
    assert set(studio_world.model_names()) == names
    choose(page, 'File', 'Exit Model Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    assert page.errors == []


def test_a_deleted_robot_comes_back_with_its_plugins(open_page, studio_world):
    page = open_page()
    before = position(studio_world, 'my_robot')
    select(page, 'my_robot')
    page.locator('#view').focus()
    page.keyboard.press('Delete')
    wait_for(lambda: 'my_robot' not in studio_world.model_names())
    choose(page, 'Edit', 'Undo')
    wait_for(lambda: 'my_robot' in studio_world.model_names())
    assert position(studio_world, 'my_robot') == pytest.approx(before, abs=1e-3)
    # Its camera plugin is back too: the image topic has a publisher and images again.
    image = studio_world.message('/camera/rgb/image_raw', 'sensor_msgs/Image')
    assert (image['width'], image['height']) == (800, 800)
    assert page.errors == []
