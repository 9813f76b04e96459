"""The studio's keys, toolbar and Building Editor in a real browser, on a studio served from
this process over a bare Simulation (flatsim.studio.sim_world), so that a test may change
what the server holds: one keymap, a key doing one thing in each mode; the world's tools
gone while the Building Editor is open; the editor drawing with the server's grid, snap
radius, defaults and limits; and Undo and Redo of every edit in it. The editor's geometry
alone runs under node's test runner (test_the_building_geometry_passes_nodes_test_runner)."""
import os
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET

import pytest
from playwright.sync_api import expect

from flatsim.authoring import building
from flatsim.loading.sdf_world import parse_world
from flatsim.ros.studio_world import client_dirs
from flatsim.studio import editors
from flatsim.studio.hub import Hub
from flatsim.studio.server import StudioServer
from flatsim.studio.sim_world import SimWorld
from flatsim.world.sim import Simulation
from studio_browser import browser_context, choose, fill, new_page, wait_for  # noqa: F401

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STUDIO_WEB = os.path.join(TOP, 'catkin_ws', 'src', 'flatsim', 'studio_web')
WORLD = '''<sdf version="1.6"><world name="keys">
  <model name="ground_plane"><static>true</static><link name="link">
    <collision name="c"><geometry><plane><normal>0 0 1</normal><size>40 40</size></plane></geometry></collision>
    <visual name="v"><geometry><plane><normal>0 0 1</normal><size>40 40</size></plane></geometry></visual>
  </link></model>
  <model name="white_ball"><pose>3 3 0.1 0 0 0</pose><link name="link">
    <collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
    <visual name="v"><geometry><sphere><radius>0.1</radius></sphere></geometry></visual>
  </link></model>
</world></sdf>'''


@pytest.fixture(scope='module')
def home(tmp_path_factory):
    home = tmp_path_factory.mktemp('home')
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv('HOME', str(home))
        yield home


@pytest.fixture(scope='module')
def studio(home):
    sim = Simulation(parse_world(WORLD))
    hub = Hub(SimWorld(sim, 'keys.world'))
    editors.install(hub)
    server = StudioServer(hub, *client_dirs())
    server.start()
    yield server
    server.stop()


@pytest.fixture
def open_page(browser_context, studio):
    pages = []

    def open_one():
        page = new_page(browser_context, studio.url)
        pages.append(page)
        return page

    yield open_one
    for page in pages:
        if not page.is_closed():
            page.close()


def models(studio):
    return sorted(model['name'] for model in studio.hub.world.scene()['models'])


def keydown_listeners(page, where):
    """The page's own keydown listeners on its window or document (three.js's controls, which
    listen for the Ctrl key alone, are not the page's), as the browser counts them."""
    cdp = page.context.new_cdp_session(page)
    scripts = {}
    cdp.on('Debugger.scriptParsed', lambda event: scripts.__setitem__(event['scriptId'], event['url']))
    cdp.send('Debugger.enable')
    target = cdp.send('Runtime.evaluate', {'expression': where})['result']['objectId']
    listeners = cdp.send('DOMDebugger.getEventListeners', {'objectId': target})['listeners']
    cdp.detach()
    assert scripts, 'the browser named no scripts'
    return [listener for listener in listeners if listener['type'] == 'keydown'
            and '/three/' not in scripts[listener['scriptId']]]


def floor_click(page, x, y, **options):
    point = page.evaluate('([x, y]) => window.studio.buildingEditor.screenPoint(x, y)', [x, y])
    page.mouse.click(point['x'], point['y'], **options)


def design(page):
    return page.evaluate('() => window.studio.buildingEditor.design')


def walls(page):
    return [[wall['start'], wall['end']] for wall in design(page)['walls']]


def test_one_keydown_listener_and_a_key_does_one_thing_in_each_mode(open_page, studio):
    page = open_page()
    # The page's keys are read in one place: the keymap's listener.
    assert len(keydown_listeners(page, 'window')) + len(keydown_listeners(page, 'document')) == 1
    keymap = page.evaluate('() => window.studio.keymap.describe()')
    assert keymap['world']['Delete'] == 'delete'
    assert keymap['building']['Delete'] == 'deleteSelected'
    assert keymap['world']['Ctrl+s'] == 'saveWorld'
    assert keymap['building']['Ctrl+s'] == keymap['model']['Ctrl+s'] == 'save'
    assert keymap['building']['Ctrl+z'] == 'undo' and keymap['building']['Ctrl+Shift+z'] == 'redo'
    assert keymap['world']['t'] == 'translationMode' and 't' not in keymap['building']
    # The Scale tool's s is the world's; the model menu's Esc is the world's Esc (no listener of its own).
    assert keymap['world']['s'] == 'scale' and 's' not in keymap['building']
    assert keymap['world']['Escape'] == 'selectionMode' and keymap['model']['Escape'] == 'closeModelMenu'

    # In the Building Editor, t and Delete are not the world's.
    page.get_by_role('list', name='Models').get_by_role('button', name='white_ball').click()
    page.keyboard.press('Control+b')
    expect(page.locator('body')).to_have_attribute('data-mode', 'building')
    page.keyboard.press('t')
    page.keyboard.press('Delete')
    assert page.evaluate('() => window.studio.view.mode') == 'select'
    choose(page, 'File', 'Exit Building Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    expect(page.locator('body')).to_have_attribute('data-mode', 'world')
    assert 'white_ball' in models(studio)

    # No key is a hotkey while a field is typed in: t and Delete there are the field's.
    field = page.get_by_role('spinbutton', name='x', exact=True)
    field.click()
    page.keyboard.press('t')
    page.keyboard.press('Delete')
    assert page.evaluate('() => window.studio.view.mode') == 'select'
    assert 'white_ball' in models(studio)
    # Out of it, they are again.
    field.blur()
    page.keyboard.press('t')
    assert page.evaluate('() => window.studio.view.mode') == 'translate'
    page.keyboard.press('Escape')
    assert page.evaluate('() => window.studio.view.mode') == 'select'
    assert page.errors == []


def test_the_worlds_tools_are_gone_under_the_building_editor_and_a_click_drops_nothing(open_page, studio):
    page = open_page()
    toolbar = page.get_by_role('toolbar', name='Tools')
    box = toolbar.get_by_role('button', name='Box', exact=True)
    translate = toolbar.get_by_role('button', name='Translation Mode')
    placing = page.locator('p.placing')
    expect(box).to_be_visible()
    before = models(studio)
    # A Box being placed when the editor opens is dropped nowhere: the world is out of sight.
    box.click()
    expect(placing).to_contain_text('place Box')
    page.keyboard.press('Control+b')
    for tool in (box, translate, toolbar.get_by_role('button', name='Copy')):
        expect(tool).to_be_hidden()
    expect(placing).to_have_text('')
    floor_click(page, 1.0, 1.0)
    floor_click(page, 2.0, -1.0)
    assert models(studio) == before
    # The editor had the clicks: one selected nothing, and no wall tool was in hand.
    assert walls(page) == []
    choose(page, 'File', 'Exit Building Editor')
    page.get_by_role('dialog', name='Save Changes').get_by_role('button', name="Don't Save, Exit").click()
    expect(box).to_be_visible()
    expect(translate).to_be_visible()
    assert models(studio) == before
    assert page.errors == []


def test_the_editor_draws_with_the_grid_snap_defaults_and_limits_the_server_holds(open_page, studio,
                                                                                  monkeypatch):
    # Held once, in the module that checks buildings: changed there, the page follows.
    monkeypatch.setattr(building, 'GRID_STEP', 0.5)
    monkeypatch.setattr(building, 'END_SNAP_RADIUS', 0.6)
    monkeypatch.setattr(building, 'WALL_HEIGHT', 3.0)
    monkeypatch.setattr(editors, 'MAX_PARTS', 2)
    page = open_page()
    choose(page, 'Edit', 'Building Editor')
    editor = page.get_by_role('region', name='Building Editor')
    expect(page.get_by_label('Building Editor drawing: the floor from above, 0.5 m grid')).to_be_visible()
    editor.get_by_role('button', name='Wall').click()
    floor_click(page, 0.3, 0.1)          # the 0.5 m grid: (0.5, 0), not (0.25, 0)
    floor_click(page, 2.2, 0.2)          # (2, 0)
    floor_click(page, 2.45, 1.85)        # (2.5, 2): no wall end within 0.6 m
    assert walls(page) == [[[0.5, 0], [2, 0]], [[2, 0], [2.5, 2]]]
    # A third wall is more than the server reads: refused in the page, with why.
    floor_click(page, 0.6, 2.4)
    expect(page.get_by_role('alert')).to_contain_text('A building may have 2 walls at most')
    assert len(walls(page)) == 2
    page.keyboard.press('Escape')
    # A new wall is as high as the server says.
    floor_click(page, 1.0, 0.05)
    wall = editor.get_by_role('group', name='Wall Inspector')
    expect(wall.get_by_role('spinbutton', name='Height')).to_have_value('3')
    page.keyboard.press('Delete')
    assert walls(page) == [[[2, 0], [2.5, 2]]]
    # Ends within the snap radius (0.6 m) go to another wall's end.
    editor.get_by_role('button', name='Wall').click()
    floor_click(page, 2.4, 2.45)         # (2.5, 2), the end 0.46 m away
    floor_click(page, 0.3, 2.3)          # (0.5, 2.5)
    assert walls(page)[1] == [[2.5, 2], [0.5, 2.5]]
    assert page.errors == []


def wall_count_saved(home, name):
    sdf = ET.parse(str(home / 'building_editor_models' / name / 'model.sdf'))
    return len([link for link in sdf.iter('link') if re.fullmatch(r'Wall_\d+', link.get('name'))])


def test_undo_and_redo_every_edit_in_the_building_editor(open_page, home):
    page = open_page()
    page.keyboard.press('Control+b')
    editor = page.get_by_role('region', name='Building Editor')
    # Nothing to undo yet: Edit > Undo says so.
    page.get_by_role('button', name='Edit', exact=True).click()
    expect(page.get_by_role('menuitem', name='Undo')).to_have_attribute('aria-disabled', 'true')
    page.get_by_role('button', name='Edit', exact=True).click()

    editor.get_by_role('button', name='Wall').click()
    for corner in ((0, 0), (3, 0), (3, 2), (0, 2)):
        floor_click(page, *corner)
    page.keyboard.press('Escape')
    assert len(walls(page)) == 3
    # Add wall: Ctrl+Z takes the walls back one by one, Ctrl+Shift+Z puts them again.
    page.keyboard.press('Control+z')
    page.keyboard.press('Control+z')
    assert walls(page) == [[[0, 0], [3, 0]]]
    page.keyboard.press('Control+Shift+z')
    assert walls(page) == [[[0, 0], [3, 0]], [[3, 0], [3, 2]]]
    page.keyboard.press('Control+Shift+z')
    assert len(walls(page)) == 3
    # Door added, and undone.
    editor.get_by_role('button', name='Door').click()
    floor_click(page, 1.5, 0.05)
    expect(editor.get_by_role('group', name='Door Inspector')).to_be_visible()
    assert len(design(page)['openings']) == 1
    page.locator('.building-canvas').focus()
    page.keyboard.press('Control+z')
    assert design(page)['openings'] == []
    expect(editor.get_by_role('group', name='Door Inspector')).to_be_hidden()
    page.keyboard.press('Control+Shift+z')
    assert len(design(page)['openings']) == 1
    # Wall deleted (with its door), and undone: both back.
    floor_click(page, 0.5, 0.05)
    expect(editor.get_by_role('group', name='Wall Inspector')).to_be_visible()
    page.keyboard.press('Delete')
    assert len(walls(page)) == 2 and design(page)['openings'] == []
    page.keyboard.press('Control+z')
    assert walls(page)[0] == [[0, 0], [3, 0]] and len(design(page)['openings']) == 1
    # A wall moved in the inspector, and a door's width: Edit > Undo and Edit > Redo.
    floor_click(page, 3.05, 1.0)
    wall = editor.get_by_role('group', name='Wall Inspector')
    fill(wall, 'spinbutton', 'End Y', '4')
    assert walls(page)[1] == [[3, 0], [3, 4]]
    choose(page, 'Edit', 'Undo')
    assert walls(page)[1] == [[3, 0], [3, 2]]
    expect(wall.get_by_role('spinbutton', name='End Y')).to_have_value('2')
    choose(page, 'Edit', 'Redo')
    assert walls(page)[1] == [[3, 0], [3, 4]]
    floor_click(page, 1.5, 0.05)
    door = editor.get_by_role('group', name='Door Inspector')
    fill(door, 'spinbutton', 'Width', '1.2')
    choose(page, 'Edit', 'Undo')
    assert design(page)['openings'][0]['width'] == 0.9
    expect(door.get_by_role('spinbutton', name='Width')).to_have_value('0.9')
    # Door deleted, and undone.
    door.get_by_role('button', name='Delete').click()
    assert design(page)['openings'] == []
    choose(page, 'Edit', 'Undo')
    assert len(design(page)['openings']) == 1
    # Back through the wall's end, the door and the third wall; what is saved is what Undo left.
    for _ in range(3):
        choose(page, 'Edit', 'Undo')
    assert walls(page) == [[[0, 0], [3, 0]], [[3, 0], [3, 2]]] and design(page)['openings'] == []
    choose(page, 'File', 'Save As')
    dialog = page.get_by_role('dialog', name='Save Model')
    dialog.get_by_role('textbox', name='Model Name:').fill('undone')
    dialog.get_by_role('button', name='Save', exact=True).click()
    expect(dialog).to_have_count(0)
    assert wall_count_saved(home, 'undone') == 2
    assert page.errors == []


def test_the_building_geometry_passes_nodes_test_runner():
    node = shutil.which('node') or shutil.which('nodejs')
    assert node, "Debian's nodejs (setup.sh installs it) runs the page's pure modules' tests"
    result = subprocess.run([node, '--test', 'test/'], cwd=STUDIO_WEB, capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-2000:]
    # Every test file ran, and none was left out.
    assert re.search(r'^# pass [1-9]\d*$', result.stdout, re.M)
    assert re.search(r'^# fail 0$', result.stdout, re.M)
