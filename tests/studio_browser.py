"""Fixtures for tests of the studio (Gazebo's window as a web page) in a real browser.

A test module imports the fixtures it uses:

    from studio_browser import browser_context, open_page, studio_world  # noqa: F401

    def test_the_ball_is_listed(open_page):
        page = open_page()                       # a new tab on the studio, scene shown
        expect(page.get_by_role('button', name='white_ball')).to_be_visible()

studio_world (module scope): roscore on a free port and the project's world
    with the robot (`roslaunch my_robot world.launch gui:=false`), with
    ROS_HOME in a temporary folder. A StudioWorld: .url (the page's address with
    its token), .ros (tests/rosproc.RosSystem), .simulator_pid(), .model_state(name),
    .call(service, type, request_dict) (a forked rospy client), .sim_time(), .param(name),
    .message(topic, type).
browser_context (module scope): Debian's /usr/bin/chromium, headless, driven by
    Playwright, on a fresh user data dir; never a downloaded browser.
open_page (function scope): open_page(url=None) opens a tab (default: the
    studio_world's page), waits until the scene and its poses are shown, and
    closes it at the end of the test.

start_studio_world(log_dir, launch_args), launch_browser(user_data_dir) and
new_page(context, url) are the same without pytest, for benchmarks and other
worlds. Page helpers: wait_ready(page), page_pose(page, model),
page_sim_time(page), choose(page, menu, entry), fill(scope, role, name, value),
floor_point_on_screen(page, x, y), drop(page, x, y), model_my_ball(page),
save_as(page, name), screenshot(page, name, tmp_path).
"""
import contextlib
import os

import pytest
from playwright.sync_api import expect

from rosproc import RosSystem, run_forked, wait_until

CHROMIUM = '/usr/bin/chromium'
# Headless, no GPU (WebGL through SwiftShader), and nothing that reaches the network.
CHROMIUM_ARGS = ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
                 '--disable-background-networking', '--disable-component-update',
                 '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
                 # Tabs in the background keep running, as windows side by side would.
                 '--disable-background-timer-throttling', '--disable-renderer-backgrounding',
                 '--disable-backgrounding-occluded-windows']
VIEWPORT = {'width': 1280, 'height': 760}
READY_TIMEOUT_MS = 30000
# Every edit makes a round trip through the simulator, beside a browser that renders in
# software: on a busy two-CPU machine that takes seconds, so assertions on the page wait
# longer than Playwright's 5 s before they fail.
EXPECT_TIMEOUT_MS = 15000
expect.set_options(timeout=EXPECT_TIMEOUT_MS)
PROJECT_WORLD = ('my_robot', 'world.launch', 'gui:=false')
EMPTY_WORLD = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'catkin_ws', 'src',
                           'my_robot', 'worlds', 'empty.world')
# The course robot in the empty world, 2 m west of the origin, where the tests drop models.
ROBOT_X = -2.0


class StudioWorld:
    """A running world on a master of its own, whose studio tests open."""

    def __init__(self, ros, home):
        self.ros = ros
        self.home = home
        self.url = None

    def address_file(self):
        from flatsim.studio import address
        return address.address_path(self.ros.master_uri, home=self.home)

    def wait_for_studio(self, timeout=60.0):
        from flatsim.studio import address
        found = wait_until(lambda: address.read_address(self.address_file()), timeout)
        if not found:
            raise RuntimeError('the studio did not write its address to %s' % self.address_file())
        self.url = found['url']
        return self.url

    def simulator_pid(self):
        return self.ros.graph.node_pid('/flatsim')

    def call(self, service, service_type, request=None):
        """Call a ROS service from a forked rospy node; returns the response as a dict of fields."""
        return run_forked(_call_service, self.ros.master_uri, service, service_type, request or {})

    def model_state(self, name):
        return self.call('/gazebo/get_model_state', 'gazebo_msgs/GetModelState', {'model_name': name})

    def model_names(self):
        return self.call('/gazebo/get_world_properties', 'gazebo_msgs/GetWorldProperties')['model_names']

    def sim_time(self):
        return self.call('/gazebo/get_world_properties', 'gazebo_msgs/GetWorldProperties')['sim_time']

    def param(self, name):
        return run_forked(_get_param, self.ros.master_uri, name)

    def message(self, topic, message_type, timeout=30.0):
        """The next message on topic, as a dict of fields (a forked rospy subscriber)."""
        return run_forked(_next_message, self.ros.master_uri, topic, message_type, timeout)


def _plain(value):
    """A ROS message as plain values (dicts, lists, seconds), to pass out of a forked child."""
    import genpy
    if isinstance(value, genpy.Message):
        return {slot: _plain(getattr(value, slot)) for slot in value.__slots__}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, genpy.rostime.TVal):
        return value.to_sec()
    return value


def _ros_client(master_uri):
    os.environ['ROS_MASTER_URI'] = master_uri
    os.environ.setdefault('ROS_HOSTNAME', 'localhost')
    import rospy
    rospy.init_node('studio_test', anonymous=True, disable_signals=True)
    return rospy


def _call_service(master_uri, service, service_type, request):
    rospy = _ros_client(master_uri)
    from roslib.message import get_service_class
    rospy.wait_for_service(service, timeout=30.0)
    import genpy
    kind = get_service_class(service_type)
    message = kind._request_class()
    # Nested dicts become nested messages, as rosservice call reads YAML.
    genpy.message.fill_message_args(message, [request])
    result = _plain(rospy.ServiceProxy(service, kind)(message))
    rospy.signal_shutdown('done')
    return result


def _get_param(master_uri, name):
    import rosgraph
    return rosgraph.Master('/studio_test', master_uri=master_uri).getParam(name)


def _next_message(master_uri, topic, message_type, timeout):
    rospy = _ros_client(master_uri)
    from roslib.message import get_message_class
    result = _plain(rospy.wait_for_message(topic, get_message_class(message_type), timeout=timeout))
    rospy.signal_shutdown('done')
    return result


@contextlib.contextmanager
def start_studio_world(log_dir, launch_args=PROJECT_WORLD, env=None):
    """A master and `roslaunch <launch_args>` on free ports, until the studio answers.

    env: variables to set for them (HOME, so that ~/.gazebo and the editors' folders are private).
    """
    home = os.path.join(str(log_dir), 'ros_home')
    os.makedirs(home, exist_ok=True)
    ros = RosSystem(log_dir, env=dict(os.environ, ROS_HOME=home, **(env or {})))
    with ros:
        world = StudioWorld(ros, home)
        ros.launch('world', *launch_args)
        ros.graph.wait_for_service('/gazebo/get_model_state')
        world.wait_for_studio()
        yield world


def launch_browser(playwright, user_data_dir):
    """A persistent browser context on Debian's chromium, headless, in user_data_dir."""
    return playwright.chromium.launch_persistent_context(
        str(user_data_dir), executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS,
        viewport=VIEWPORT)


def wait_ready(page, timeout_ms=READY_TIMEOUT_MS):
    """Wait until the page shows the scene and the poses that follow it."""
    page.wait_for_selector('body[data-ready="true"]', state='attached', timeout=timeout_ms)


def page_pose(page, model):
    """The pose the page shows for a model, as the simulator last streamed it."""
    return page.evaluate('(name) => window.studio.poses[name] || null', model)


def page_sim_time(page):
    return page.evaluate('() => window.studio.status ? window.studio.status.sim_time : null')


def choose(page, menu, entry):
    """Click menu in the menu bar shown now (the window's, or an open editor's), then entry."""
    page.get_by_role('button', name=menu, exact=True).click()
    page.get_by_role('menuitem', name=entry, exact=True).click()


def fill(scope, role, name, value):
    """Type value into the field of that role and name in scope, and press Enter."""
    field = scope.get_by_role(role, name=name, exact=True)
    field.fill(value)
    field.press('Enter')


def model_my_ball(page):
    """The course's white ball in the Model Editor, not saved yet: Edit > Model Editor, a
    sphere, radius 0.1, Ambient, Diffuse, Specular and Emissive 1. Returns its Link Inspector."""
    choose(page, 'Edit', 'Model Editor')
    editor = page.get_by_role('region', name='Model Editor')
    editor.get_by_role('group', name='Simple Shapes').get_by_role('button', name='Sphere').click()
    inspector = editor.get_by_role('group', name='Link Inspector')
    inspector.get_by_role('tab', name='Visual').click()
    fill(inspector, 'spinbutton', 'Radius', '0.1')
    for colour in ('Ambient', 'Diffuse', 'Specular', 'Emissive'):
        fill(inspector, 'textbox', colour, '1 1 1 1')
    return inspector


def save_as(page, name):
    """An editor's File > Save As under name, in the default folder; returns the dialog."""
    choose(page, 'File', 'Save As')
    dialog = page.get_by_role('dialog', name='Save Model')
    dialog.get_by_role('textbox', name='Model Name:').fill(name)
    dialog.get_by_role('button', name='Save', exact=True).click()
    return dialog


def floor_point_on_screen(page, x, y):
    """Where the floor point (x, y) is in the page's 3D view, in page pixels."""
    return page.evaluate('''([x, y]) => {
        const view = window.studio.view;
        return view.screenPointOf(view.camera.position.clone().set(x, y, 0)); }''', [x, y])


def drop(page, x, y):
    """Click the floor point (x, y) in the view, as Insert's placing waits for."""
    point = floor_point_on_screen(page, x, y)
    page.mouse.click(point['x'], point['y'])


def screenshot(page, name, tmp_path):
    """A screenshot for the docs: in STUDIO_SCREENSHOTS (a folder, such as docs) when set,
    else in tmp_path, so that a test run leaves the checkout as it was."""
    path = os.path.join(os.environ.get('STUDIO_SCREENSHOTS') or str(tmp_path), name)
    page.screenshot(path=path)
    return path


def wait_for(predicate, timeout=15.0):
    """Poll predicate (wall time) until truthy; returns its value or raises AssertionError."""
    value = wait_until(predicate, timeout, interval=0.05)
    if not value:
        raise AssertionError('not within %g s of wall time' % timeout)
    return value


@pytest.fixture(scope='module')
def studio_world(tmp_path_factory):
    with start_studio_world(tmp_path_factory.mktemp('studio')) as world:
        yield world


@pytest.fixture(scope='module')
def browser_context(tmp_path_factory):
    from playwright.sync_api import sync_playwright
    with sync_playwright() as playwright:
        context = launch_browser(playwright, tmp_path_factory.mktemp('chromium'))
        yield context
        context.close()


def new_page(context, url):
    """A tab of context on the studio at url, once it shows the scene; page.errors collects
    the page's uncaught errors."""
    page = context.new_page()
    page.errors = []
    page.on('pageerror', lambda error: page.errors.append(str(error)))
    page.goto(url)
    wait_ready(page)
    return page


@pytest.fixture
def open_page(browser_context, studio_world):
    pages = []

    def open_one(url=None):
        page = new_page(browser_context, url or studio_world.url)
        pages.append(page)
        return page

    yield open_one
    for page in pages:
        if not page.is_closed():
            page.close()


def start_empty_world(log_dir, home):
    """start_studio_world with the course robot at ROBOT_X in the empty world, and HOME home."""
    launch = ('my_robot', 'world.launch', 'gui:=false', 'world_file:=%s' % EMPTY_WORLD, 'x:=%g' % ROBOT_X)
    return start_studio_world(log_dir, launch, env={'HOME': str(home)})
