"""The studio in a real browser: the project's world (my_robot world.launch), one or
more tabs on it, and the simulator's own answers (/gazebo/get_model_state) to check
what the page did. The last test takes the screenshot docs/course.md shows:

    STUDIO_SCREENSHOT=docs/studio.png python -m pytest tests/test_studio.py -k screenshot

(without STUDIO_SCREENSHOT it goes to the test's temporary folder, so that a test run
leaves the checkout as it was)."""
import asyncio
import concurrent.futures
import http.server
import json
import math
import os
import signal
import subprocess
import threading
import urllib.error
import urllib.parse
import urllib.request

import aiohttp
import pytest
from playwright.sync_api import expect

from rosproc import is_loopback, listening_sockets
from studio_browser import (browser_context, open_page, page_pose, page_sim_time,  # noqa: F401
                            start_studio_world, studio_world, wait_for, wait_ready)

STEP_SIZE = 0.002


def ball_state(world):
    position = world.model_state('white_ball')['pose']['position']
    return position['x'], position['y']


def select(page, model):
    page.get_by_role('button', name=model).click()
    return page.get_by_role('group', name='%s pose' % model)


def set_field(page, model, field, value):
    box = select(page, model).get_by_role('spinbutton', name=field, exact=True)
    box.fill(str(value))
    box.press('Enter')


def edit(page, entry):
    page.get_by_role('button', name='Edit', exact=True).click()
    page.get_by_role('menuitem', name=entry, exact=True).click()


def grab_handle(page, model, axis='XY'):
    """Select model, translation mode, and press the mouse on its handle; returns the point."""
    select(page, model)
    page.keyboard.press('t')
    point = page.evaluate('(axis) => window.studio.view.handlePoint(axis)', axis)
    assert point is not None, 'no %s handle on %s' % (axis, model)
    page.mouse.move(point['x'], point['y'])
    page.mouse.down()
    # A few steps, so that the handle sees a drag rather than a click.
    for step in range(1, 6):
        page.mouse.move(point['x'] + 12 * step, point['y'] + 6 * step)
    return point


def test_the_world_appears_with_its_models_listed(open_page):
    page = open_page()
    models = page.get_by_role('list', name='Models')
    for name in ('white_ball', 'my_robot', 'building', 'table'):
        expect(models.get_by_role('button', name=name)).to_be_visible()
    # The robot's lidar mesh is drawn: nothing of the course's world is skipped.
    expect(page.get_by_role('heading', name='Skipped by flatsim (0)')).to_be_visible()
    expect(page.get_by_role('status', name='Connection')).to_have_text('Connected to the simulator')
    drawn = page.evaluate('() => [...window.studio.view.models.keys()]')
    assert {'white_ball', 'my_robot', 'building'} <= set(drawn)
    assert page.errors == []


def test_clicking_a_model_in_the_view_selects_it(open_page):
    page = open_page()
    point = page.evaluate('''() => {
        const view = window.studio.view;
        return view.screenPointOf(view.models.get('white_ball').group.position); }''')
    page.mouse.click(point['x'], point['y'])
    expect(page.get_by_role('button', name='white_ball')).to_have_attribute('aria-selected', 'true')
    expect(page.get_by_role('group', name='white_ball pose')).to_be_visible()
    # Top View: straight down on the point the view turns about.
    page.get_by_role('button', name='Top View').click()
    camera, target = page.evaluate('''() => {
        const view = window.studio.view;
        return [view.camera.position.toArray(), view.orbit.target.toArray()]; }''')
    assert camera[:2] == pytest.approx(target[:2], abs=0.01) and camera[2] > target[2] + 1.0
    # A click on no model (the far floor, top left of the view) selects nothing.
    view = page.locator('#view').bounding_box()
    page.mouse.click(view['x'] + 15, view['y'] + 15)
    expect(page.get_by_role('button', name='white_ball')).to_have_attribute('aria-selected', 'false')


def test_gzclient_prints_the_address_of_the_world_running_now(studio_world):
    env = dict(studio_world.ros.env)
    env.pop('DISPLAY', None)
    client = subprocess.Popen(['gzclient'], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        line = client.stdout.readline()
    finally:
        client.send_signal(signal.SIGTERM)
        client.wait(20)
    assert line.strip() == "gzclient: Gazebo's window (flatsim studio) is at %s" % studio_world.url


def test_a_mouse_drag_and_the_pose_fields_move_the_ball_in_the_simulator(open_page, studio_world):
    page = open_page()
    before = ball_state(studio_world)
    point = grab_handle(page, 'white_ball')
    page.mouse.move(point['x'] + 150, point['y'] + 40, steps=8)
    page.mouse.up()
    moved = wait_for(lambda: (lambda now: now if abs(now[0] - before[0]) + abs(now[1] - before[1]) > 0.2
                              else None)(ball_state(studio_world)))
    # The page shows what the simulator has, not what the mouse left behind.
    shown = wait_for(lambda: (lambda p: p if abs(p[0] - moved[0]) < 1e-3 else None)(
        page_pose(page, 'white_ball')))
    assert shown[1] == pytest.approx(moved[1], abs=1e-3)
    set_field(page, 'white_ball', 'x', 1.25)
    set_field(page, 'white_ball', 'y', -0.75)
    wait_for(lambda: ball_state(studio_world) == pytest.approx((1.25, -0.75), abs=1e-3))
    assert page.errors == []


def crate_state(world):
    position = world.model_state('crate')['pose']['position']
    return position['x'], position['y'], position['z']


def test_a_static_model_is_dragged_by_its_handle_and_reset_back(open_page, studio_world):
    page = open_page()
    start = crate_state(studio_world)
    point = grab_handle(page, 'crate')
    page.mouse.move(point['x'] + 150, point['y'] + 40, steps=8)
    page.mouse.up()
    moved = wait_for(lambda: (lambda now: now if abs(now[0] - start[0]) + abs(now[1] - start[1]) > 0.2
                              else None)(crate_state(studio_world)))
    assert moved[2] == pytest.approx(start[2])          # the handle moves it in the plane
    shown = wait_for(lambda: (lambda p: p if abs(p[0] - moved[0]) < 1e-3 else None)(
        page_pose(page, 'crate')))
    assert shown[1] == pytest.approx(moved[1], abs=1e-3)
    edit(page, 'Reset Model Poses')
    wait_for(lambda: crate_state(studio_world) == pytest.approx(start, abs=1e-6))
    set_field(page, 'crate', 'z', 0.75)                 # a pose field: any height, as in Gazebo
    wait_for(lambda: crate_state(studio_world)[2] == pytest.approx(0.75, abs=1e-3))
    edit(page, 'Reset Model Poses')
    wait_for(lambda: crate_state(studio_world) == pytest.approx(start, abs=1e-6))
    assert page.errors == []


def robot_state(world):
    pose = world.model_state('my_robot')['pose']
    position, turn = pose['position'], pose['orientation']
    return position['x'], position['y'], 2.0 * math.atan2(turn['z'], turn['w'])


def test_a_chasing_robot_reacts_while_the_ball_is_dragged(browser_context, tmp_path):
    with start_studio_world(tmp_path) as world:
        world.ros.launch('chaser', 'ball_chaser', 'ball_chaser.launch', 'output:=log')
        world.ros.graph.wait_for_node('/process_image')
        page = browser_context.new_page()
        errors = []
        page.on('pageerror', lambda error: errors.append(str(error)))
        page.goto(world.url)
        wait_ready(page)
        # Behind the robot and to its left, out of its camera's sight: the robot waits.
        set_field(page, 'white_ball', 'x', -1.5)
        set_field(page, 'white_ball', 'y', 1.5)
        wait_for(lambda: ball_state(world) == pytest.approx((-1.5, 1.5), abs=1e-3))
        still = robot_state(world)
        grab_handle(page, 'white_ball')
        height = page_pose(page, 'white_ball')[2]
        # 1.2 m ahead of the robot, wherever its chase of the world's ball took it before.
        x, y, yaw = still
        target = (x + 1.2 * math.cos(yaw), y + 1.2 * math.sin(yaw))
        ahead = page.evaluate('([x, y, z]) => window.studio.view.screenPointOf('
                              'window.studio.view.camera.position.clone().set(x, y, z))',
                              [target[0], target[1], height])
        page.mouse.move(ahead['x'], ahead['y'], steps=12)
        # The mouse is still down: the drag goes on while the robot chases what it sees.
        wait_for(lambda: math.hypot(ball_state(world)[0] - target[0], ball_state(world)[1] - target[1]) < 0.4)
        wait_for(lambda: max(abs(a - b) for a, b in zip(robot_state(world), still)) > 0.05)
        page.mouse.up()
        assert errors == []
        page.close()


def test_rotation_mode_turns_the_robot_in_the_simulator(open_page, studio_world):
    page = open_page()
    def yaw():
        orientation = studio_world.model_state('my_robot')['pose']['orientation']
        return 2.0 * math.atan2(orientation['z'], orientation['w'])
    before = yaw()
    select(page, 'my_robot')
    page.keyboard.press('r')
    expect(page.get_by_role('button', name='Rotation Mode')).to_have_attribute('aria-pressed', 'true')
    point = page.evaluate("() => window.studio.view.handlePoint('Z')")
    assert point is not None, 'no rotation ring on my_robot'
    page.mouse.move(point['x'], point['y'])
    page.mouse.down()
    page.mouse.move(point['x'] + 60, point['y'] + 60, steps=10)
    page.mouse.up()
    wait_for(lambda: abs(math.remainder(yaw() - before, 2 * math.pi)) > 0.1)
    page.keyboard.press('Escape')
    expect(page.get_by_role('button', name='Selection Mode')).to_have_attribute('aria-pressed', 'true')
    assert page.errors == []


def test_pause_step_and_reset_world(open_page, studio_world):
    page = open_page()
    panel = page.get_by_role('contentinfo', name='Time panel')
    panel.get_by_role('button', name='Pause').click()
    expect(panel.get_by_role('button', name='Play')).to_be_visible()
    paused_at = studio_world.sim_time()
    page.wait_for_timeout(500)
    assert studio_world.sim_time() == paused_at
    panel.get_by_role('button', name='Step').click()
    wait_for(lambda: studio_world.sim_time() > paused_at)
    assert studio_world.sim_time() == pytest.approx(paused_at + STEP_SIZE, abs=1e-6)
    wait_for(lambda: page_sim_time(page) == pytest.approx(paused_at + STEP_SIZE, abs=1e-6))
    # Edit > Reset Model Poses: the ball back where the world file puts it; time goes on.
    set_field(page, 'white_ball', 'x', -1.0)
    wait_for(lambda: ball_state(studio_world)[0] == pytest.approx(-1.0, abs=1e-3))
    edit(page, 'Reset Model Poses')
    wait_for(lambda: ball_state(studio_world)[0] != pytest.approx(-1.0, abs=1e-3))
    start = ball_state(studio_world)
    assert studio_world.sim_time() == pytest.approx(paused_at + STEP_SIZE, abs=1e-6)
    # Edit > Reset World: the same, and time back to zero.
    set_field(page, 'white_ball', 'x', -1.0)
    wait_for(lambda: ball_state(studio_world)[0] == pytest.approx(-1.0, abs=1e-3))
    edit(page, 'Reset World')
    wait_for(lambda: studio_world.sim_time() < paused_at)
    assert ball_state(studio_world) == pytest.approx(start, abs=1e-6)
    panel.get_by_role('button', name='Play').click()
    wait_for(lambda: studio_world.sim_time() > 0.5)
    assert page.errors == []


def test_a_request_without_the_token_gets_403(studio_world):
    parts = urllib.parse.urlsplit(studio_world.url)
    base = '%s://%s' % (parts.scheme, parts.netloc)
    for url in (base + '/', base + '/?token=wrong', base + '/static/js/main.js',
                base + '/three/build/three.module.js'):
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(url, timeout=5)
        assert refused.value.code == 403, url
    token = urllib.parse.parse_qs(parts.query)['token'][0]
    own = {'Origin': base}

    async def handshake(query, headers):
        async with aiohttp.ClientSession() as session:
            try:
                async with session.ws_connect(base + '/ws' + query, headers=headers) as socket:
                    return json.loads((await socket.receive(timeout=10)).data)['type']
            except aiohttp.WSServerHandshakeError as error:
                return error.status

    def attempt(query, headers):
        # A thread of its own: Playwright's loop runs in this one.
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            return pool.submit(asyncio.run, handshake(query, headers)).result()

    assert attempt('', own) == 403
    assert attempt('?token=wrong', own) == 403
    # The right token from another site's page: refused too.
    assert attempt('?token=' + token, {'Origin': 'http://example.org'}) == 403
    assert attempt('?token=' + token, own) == 'hello'


class Recorder(http.server.BaseHTTPRequestHandler):
    """Another local server: a page of its own, and every request it gets, headers and all."""
    seen = []

    def do_GET(self):
        self.seen.append('%s %s\n%s' % (self.command, self.path, self.headers))
        self.send_response(200)
        self.send_header('Content-Type', 'text/html')
        self.end_headers()
        self.wfile.write(b'<p>another server</p><img src="/picture.png">')

    def log_message(self, *args):
        pass


def test_another_local_server_never_gets_what_opens_the_studio(open_page, browser_context,
                                                               studio_world):
    """On a shared machine another user's page may be served from 127.0.0.1 too, on a port of
    its own: the browser that has the studio open sends it nothing that holds the token, and
    keeps nothing it would send there. The studio's page still loads its modules."""
    studio = open_page()
    assert studio.errors == []
    token = urllib.parse.parse_qs(urllib.parse.urlsplit(studio_world.url).query)['token'][0]
    server = http.server.ThreadingHTTPServer(('127.0.0.1', 0), Recorder)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    other_url = 'http://127.0.0.1:%d/' % server.server_address[1]
    try:
        other = browser_context.new_page()
        other.goto(other_url)
        other.evaluate('fetch("/asked", {credentials: "include"}).then((answer) => answer.text())')
        other.close()
    finally:
        server.shutdown()
        thread.join(5)
    assert len(Recorder.seen) >= 2
    assert [request for request in Recorder.seen if token in request] == []
    assert browser_context.cookies(other_url) == []


def test_the_studio_listens_on_loopback_only(studio_world):
    port = urllib.parse.urlsplit(studio_world.url).port
    sockets = listening_sockets(studio_world.simulator_pid())
    studio = [address for address, listening in sockets if listening == port]
    assert studio == ['127.0.0.1']
    assert all(is_loopback(address) for address, _ in sockets)


def test_a_tab_closed_mid_drag_leaves_the_world_running_and_the_ball_free(open_page, studio_world):
    watcher = open_page()
    dragger = open_page()
    grab_handle(dragger, 'white_ball')
    wait_for(lambda: watcher.evaluate('() => Object.keys(window.studio.leases).length') == 1)
    dragger.close()
    wait_for(lambda: watcher.evaluate('() => Object.keys(window.studio.leases).length') == 0)
    shown = page_sim_time(watcher)
    wait_for(lambda: page_sim_time(watcher) > shown + 0.3)
    simulated = studio_world.sim_time()
    wait_for(lambda: studio_world.sim_time() > simulated + 0.3)
    set_field(watcher, 'white_ball', 'x', 0.75)
    wait_for(lambda: ball_state(studio_world)[0] == pytest.approx(0.75, abs=1e-3))
    assert watcher.errors == []


def test_two_tabs_see_each_others_edits(open_page, studio_world):
    first = open_page()
    second = open_page()
    set_field(first, 'white_ball', 'y', 1.5)
    wait_for(lambda: (page_pose(second, 'white_ball') or [0, 0])[1] == pytest.approx(1.5, abs=1e-3))
    set_field(second, 'white_ball', 'x', -0.5)
    wait_for(lambda: (page_pose(first, 'white_ball') or [0])[0] == pytest.approx(-0.5, abs=1e-3))
    assert ball_state(studio_world) == pytest.approx((-0.5, 1.5), abs=1e-3)


def test_a_second_tab_editing_the_same_model_gets_a_clear_message(open_page, studio_world):
    first = open_page()
    second = open_page()
    grab_handle(first, 'white_ball')
    holder = first.evaluate('() => window.studio.session')
    wait_for(lambda: second.evaluate('() => window.studio.leases.white_ball') == holder)
    expect(second.get_by_role('button', name='white_ball')).to_contain_text(
        'being edited in another window')
    set_field(second, 'white_ball', 'x', 2.5)
    expect(second.get_by_role('alert')).to_contain_text(
        'white_ball is being edited in window %d; try again when it is done there' % holder)
    first.mouse.up()
    assert ball_state(studio_world)[0] != pytest.approx(2.5, abs=1e-3)
    wait_for(lambda: second.evaluate('() => window.studio.leases.white_ball === undefined'))


def test_copy_paste_and_delete(open_page, studio_world):
    page = open_page()
    select(page, 'white_ball')
    page.keyboard.press('Control+c')
    page.keyboard.press('Control+v')
    models = page.get_by_role('list', name='Models')
    expect(models.get_by_role('button', name='white_ball_clone', exact=True)).to_be_visible()
    assert 'white_ball_clone' in studio_world.model_names()
    # The copy is selected once it is there; Delete takes it out of the simulator.
    expect(models.get_by_role('button', name='white_ball_clone', exact=True)).to_have_attribute(
        'aria-selected', 'true')
    page.locator('#view').focus()
    page.keyboard.press('Delete')
    expect(models.get_by_role('button', name='white_ball_clone', exact=True)).to_have_count(0)
    assert 'white_ball_clone' not in studio_world.model_names()
    assert 'white_ball' in studio_world.model_names()
    assert page.errors == []


def test_sensor_views_and_the_screenshot(open_page, tmp_path):
    page = open_page()
    page.get_by_role('button', name='View', exact=True).click()
    page.get_by_role('menuitemcheckbox', name='Lidar Rays').click()
    page.get_by_role('button', name='View', exact=True).click()
    page.get_by_role('menuitemcheckbox', name='Camera Field of View').click()
    page.get_by_role('button', name='Window').click()
    page.get_by_role('menuitemcheckbox', name='Camera').click()
    camera = page.get_by_role('img', name='camera image of my_robot::camera1', exact=False)
    expect(camera).to_be_visible()
    wait_for(lambda: page.evaluate(
        '() => window.studio.view.scanLines && window.studio.view.scanLines.geometry'
        '.attributes.position.count') or None)
    rays = page.evaluate('() => window.studio.view.scanLines.geometry.attributes.position.count')
    assert rays > 100
    select(page, 'my_robot')
    page.wait_for_timeout(500)
    path = os.environ.get('STUDIO_SCREENSHOT') or str(tmp_path / 'studio.png')
    page.screenshot(path=path)
    with open(path, 'rb') as picture:
        assert picture.read(8) == b'\x89PNG\r\n\x1a\n'
    assert page.errors == []
