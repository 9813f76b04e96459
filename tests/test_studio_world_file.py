"""The course's "Save your world" step in a real browser: `gazebo WORLD` (the world without
the robot), Insert my_ball outside the building, File > Save World over WORLD, and `gazebo
WORLD` again. As root, chmod keeps no one out, so the world runs as nobody (setpriv), as a
student's does: a save into a read-only folder is then refused, and the old file stays."""
import os
import shutil
import signal
import stat
import tempfile

import pytest
from playwright.sync_api import expect

from flatsim.loading.sdf_world import load_world
from rosproc import free_port, run_forked, wait_until
from studio_browser import _call_service, browser_context, choose, floor_point_on_screen, open_page  # noqa: F401
from test_studio_commands import ADDRESS, Command

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COURSE_WORLD = os.path.join(TOP, 'catkin_ws', 'src', 'my_robot', 'worlds', 'chase_house.world')
NOBODY = 65534
# Outside the house (its walls run from x = -3 to 7 and y = -4 to 4), as the course asks.
OUTSIDE = (2.0, 5.5)
MY_BALL_SDF = '''<?xml version="1.0" ?>
<sdf version="1.7"><model name="my_ball"><link name="link_0"><pose>0 0 0.1 0 0 0</pose>
  <collision name="collision"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
  <visual name="visual"><geometry><sphere><radius>0.1</radius></sphere></geometry>
    <material><ambient>1 1 1 1</ambient><diffuse>1 1 1 1</diffuse><specular>1 1 1 1</specular>
      <emissive>1 1 1 1</emissive></material></visual>
</link><static>0</static></model></sdf>
'''
MY_BALL_CONFIG = ('<?xml version="1.0" ?>\n<model><name>my_ball</name><version>1.0</version>'
                  '<sdf version="1.7">model.sdf</sdf></model>\n')


class GazeboWorld:
    """`gazebo WORLD` on a master of its own, as nobody when the tests run as root."""

    def __init__(self, area):
        self.area = area
        self.world = os.path.join(area, 'worlds', 'student.world')
        self.master_uri = 'http://localhost:%d' % free_port()
        self.env = dict(os.environ, HOME=os.path.join(area, 'home'), ROS_MASTER_URI=self.master_uri,
                        ROS_HOME=os.path.join(area, 'ros_home'), ROS_LOG_DIR=os.path.join(area, 'log'),
                        ROS_HOSTNAME='localhost')
        self.env.pop('DISPLAY', None)
        self.command = None
        self.url = None

    def start(self):
        argv = ['gazebo', self.world]
        if os.geteuid() == 0:
            argv = ['setpriv', '--reuid=%d' % NOBODY, '--regid=%d' % NOBODY, '--clear-groups'] + argv
        self.command = Command(argv, self.env)
        self.url = self.command.wait_for(ADDRESS.pattern, timeout=120.0).group(1)

    def stop(self):
        assert self.command.stop(signal.SIGINT) == 0, self.command.output[-3000:]

    def call(self, service, service_type, request=None):
        return run_forked(_call_service, self.master_uri, service, service_type, request or {})

    def poses(self):
        names = self.call('/gazebo/get_world_properties', 'gazebo_msgs/GetWorldProperties')['model_names']
        return {name: self.call('/gazebo/get_model_state', 'gazebo_msgs/GetModelState',
                                {'model_name': name})['pose']['position'] for name in names}

    def sim_time(self):
        return self.call('/gazebo/get_world_properties', 'gazebo_msgs/GetWorldProperties')['sim_time']


@pytest.fixture(scope='module')
def area():
    """A folder everyone may read: the world, a HOME with my_ball in it, a read-only folder."""
    if os.geteuid() == 0 and shutil.which('setpriv') is None:
        pytest.skip('running as root without setpriv to run the world as an unprivileged user')
    base = tempfile.mkdtemp(prefix='flatsim-gazebo-world-')
    os.chmod(base, 0o755)
    for folder in ('worlds', 'home/.gazebo/models/my_ball', 'ros_home', 'log', 'readonly'):
        os.makedirs(os.path.join(base, folder))
    shutil.copy(COURSE_WORLD, os.path.join(base, 'worlds', 'student.world'))
    ball = os.path.join(base, 'home', '.gazebo', 'models', 'my_ball')
    with open(os.path.join(ball, 'model.sdf'), 'w') as sdf:
        sdf.write(MY_BALL_SDF)
    with open(os.path.join(ball, 'model.config'), 'w') as config:
        config.write(MY_BALL_CONFIG)
    with open(os.path.join(base, 'readonly', 'old.world'), 'w') as old:
        old.write('the old world')
    if os.geteuid() == 0:
        for folder, _, files in os.walk(base):
            for path in [folder] + [os.path.join(folder, name) for name in files]:
                os.chown(path, NOBODY, NOBODY)
    os.chmod(os.path.join(base, 'readonly'), 0o555)
    yield base
    os.chmod(os.path.join(base, 'readonly'), 0o755)
    shutil.rmtree(base)


@pytest.fixture(scope='module')
def studio_world(area):
    world = GazeboWorld(area)
    world.start()
    yield world
    if world.command.proc.poll() is None:
        world.stop()


def test_insert_my_ball_outside_and_save_world_writes_over_the_world_file(open_page, studio_world):
    page = open_page()
    page.get_by_role('tab', name='Insert').click()
    page.get_by_role('button', name='my_ball').click()
    point = floor_point_on_screen(page, *OUTSIDE)
    page.mouse.click(point['x'], point['y'])
    expect(page.get_by_role('list', name='Models').get_by_role('button', name='my_ball')).to_have_count(1)
    page.locator('#view').focus()
    page.keyboard.press('Control+s')
    expect(page.get_by_role('status', name='Messages')).to_contain_text(
        'Saved the world in %s' % studio_world.world)
    saved = {model.name: model.pose for model in load_world(studio_world.world).models}
    assert {'building', 'white_ball', 'my_ball'} <= set(saved) and 'my_robot' not in saved
    assert (saved['my_ball'].x, saved['my_ball'].y) == pytest.approx(OUTSIDE, abs=0.05)
    assert page.errors == []


def test_save_world_as_into_a_read_only_folder_says_so_and_keeps_the_old_file(open_page, studio_world,
                                                                              area):
    page = open_page()
    choose(page, 'File', 'Save World As')
    dialog = page.get_by_role('dialog', name='Save World')
    # It starts in the world's folder, under the world's name.
    expect(dialog.get_by_role('textbox', name='Location:')).to_have_value(os.path.join(area, 'worlds'))
    expect(dialog.get_by_role('textbox', name='File name:')).to_have_value('student.world')
    dialog.get_by_role('button', name='Browse').click()
    chooser = page.get_by_role('dialog', name='Open Directory')
    chooser.get_by_role('button', name='Up').click()
    chooser.get_by_role('list', name='Folders').get_by_role('button', name='readonly').click()
    chooser.get_by_role('button', name='Choose').click()
    expect(chooser).to_have_count(0)
    dialog.get_by_role('textbox', name='File name:').fill('old.world')
    dialog.get_by_role('button', name='Save', exact=True).click()
    folder = os.path.join(area, 'readonly')
    # The file is there: the page asks first, as Gazebo's dialog does.
    replace = page.get_by_role('dialog', name='Replace File')
    expect(replace).to_contain_text('%s already exists. Do you want to replace it?'
                                    % os.path.join(folder, 'old.world'))
    replace.get_by_role('button', name='Replace').click()
    says = 'cannot write in the folder %s: Permission denied' % folder
    expect(page.get_by_role('alert')).to_contain_text(says)
    # The page may show the refusal before the simulator's log line has been read.
    assert wait_until(lambda: says in studio_world.command.output, 10.0), studio_world.command.output[-3000:]
    with open(os.path.join(folder, 'old.world')) as old:
        assert old.read() == 'the old world'
    assert os.listdir(folder) == ['old.world']
    # Nothing lost: the dialog is still there, to choose another folder.
    expect(dialog.get_by_role('textbox', name='File name:')).to_have_value('old.world')
    dialog.get_by_role('button', name='Cancel').click()
    before = studio_world.sim_time()
    assert wait_until(lambda: studio_world.sim_time() > before + 0.1, 15.0), (
        'the simulator stopped at %s s: %s\n%s' % (before, studio_world.call(
            '/gazebo/get_physics_properties', 'gazebo_msgs/GetPhysicsProperties'),
            studio_world.command.output[-3000:]))
    assert stat.S_IMODE(os.stat(folder).st_mode) == 0o555


def test_gazebo_opens_the_saved_world_with_the_same_models_where_they_were(studio_world):
    before = studio_world.poses()
    studio_world.stop()
    studio_world.start()
    after = studio_world.poses()
    assert set(after) == set(before)
    for name, where in before.items():
        assert (after[name]['x'], after[name]['y']) == pytest.approx((where['x'], where['y']), abs=1e-3), name
