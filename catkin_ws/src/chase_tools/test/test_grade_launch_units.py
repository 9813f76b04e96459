"""A submission's launch files as the grader runs them: what ball_chaser.launch starts, the
launch files' copies, the world's launch, and the world and its models read through the
grader's copy. No master."""
import os
import sys
import tempfile
import xml.etree.ElementTree as ET

import pytest

from chase_tools.grading import headless_launch, submission, worldcopy
from flatsim.loading.sdf_world import load_world

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402


# -- what ball_chaser.launch starts ---------------------------------------------------------------

def _launch(path, body):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w') as stream:
        stream.write('<launch>\n%s\n</launch>\n' % body)


INCLUDED_THROUGH_ANOTHER_FILE = """
  <arg name="world" default="true"/>
  <arg name="robot_pkg" default="$(find my_robot)"/>
  <group if="$(arg world)">
    <include file="$(dirname)/all.launch" pass_all_args="true"/>
  </group>"""
ALL_LAUNCH = """
  <arg name="robot_pkg"/>
  <include file="$(arg robot_pkg)/launch/world.launch"/>"""


def _includes_world(found, tmp_path):
    """chaser_launch_includes_world on a fresh copy of the submission, as the grader builds it."""
    src = tempfile.mkdtemp(dir=str(tmp_path), prefix='src_')
    submission.copy_packages(found, src)
    return submission.chaser_launch_includes_world(found, src)


def test_a_ball_chaser_launch_that_includes_world_launch_is_seen_through_other_files(tmp_path):
    path = variants.compose('py_chaser_includes_world', tmp_path)
    found = submission.find(path)
    assert _includes_world(found, tmp_path) == [
        os.path.join('ball_chaser', 'launch', 'ball_chaser.launch'),
        os.path.join('my_robot', 'launch', 'world.launch')]
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'),
            INCLUDED_THROUGH_ANOTHER_FILE)
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'all.launch'), ALL_LAUNCH)
    assert _includes_world(found, tmp_path) == [
        os.path.join('ball_chaser', 'launch', 'ball_chaser.launch'),
        os.path.join('ball_chaser', 'launch', 'all.launch'),
        os.path.join('my_robot', 'launch', 'world.launch')]


def test_the_include_chain_is_named_by_its_place_in_a_repository(tmp_path):
    path = variants.compose('py_repository', tmp_path)
    _launch(os.path.join(path, 'Project 2', 'ball_chaser', 'launch', 'ball_chaser.launch'),
            '<include file="$(find my_robot)/launch/world.launch"/>')
    assert _includes_world(submission.find(path), tmp_path) == [
        os.path.join('Project 2', 'ball_chaser', 'launch', 'ball_chaser.launch'),
        os.path.join('Project 2', 'my_robot', 'launch', 'world.launch')]


WORLD_INCLUDE = '<include file="$(find my_robot)/launch/world.launch"/>'
BOMB = ('<?xml version="1.0"?>\n<!DOCTYPE launch [\n<!ENTITY a "aaaaaaaaaa">\n'
        + ''.join('<!ENTITY %s "&%s;&%s;&%s;&%s;&%s;&%s;&%s;&%s;&%s;&%s;">\n'
                  % ((chr(ord('a') + level),) + (chr(ord('a') + level - 1),) * 10)
                  for level in range(1, 9))
        + ']>\n<launch>%s<arg name="x" default="&i;"/></launch>\n' % WORLD_INCLUDE)


def test_the_includes_are_read_from_the_graders_copy_never_from_the_submission(tmp_path):
    """The grader (root) reads the copy it built from, without links; a change to the
    submission after the copy, such as a launch file that now includes world.launch, is unseen."""
    path = variants.compose('py_correct', tmp_path)
    found = submission.find(path)
    src = str(tmp_path / 'src')
    submission.copy_packages(found, src)
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'), WORLD_INCLUDE)
    assert submission.chaser_launch_includes_world(found, src) == []
    _launch(os.path.join(src, 'ball_chaser', 'launch', 'ball_chaser.launch'), WORLD_INCLUDE)
    assert len(submission.chaser_launch_includes_world(found, src)) == 2
    # A link in the copy (the build may make one) is not followed.
    target = os.path.join(src, 'ball_chaser', 'launch', 'ball_chaser.launch')
    os.rename(target, str(tmp_path / 'elsewhere.launch'))
    os.symlink(str(tmp_path / 'elsewhere.launch'), target)
    assert submission.chaser_launch_includes_world(found, src) == []


@pytest.mark.parametrize('text', [
    '<!DOCTYPE launch [<!ENTITY world \'%s\'>]><launch>&world;</launch>' % WORLD_INCLUDE,
    BOMB,
    '<launch>%s<!-- %s --></launch>' % (WORLD_INCLUDE, 'x' * submission.LAUNCH_READ_LIMIT),
    '<launch>%s%s%s</launch>' % ('<group>' * 5000, WORLD_INCLUDE, '</group>' * 5000),
], ids=['entity', 'billion_laughs', 'too_large', 'too_deep'])
def test_a_launch_file_too_large_or_with_entities_is_not_read(tmp_path, text):
    """Each would be followed to world.launch if it were read: an entity that expands to the
    include, a billion laughs (eight levels of ten entities), a file larger than the grader
    reads, an include inside groups nested 5,000 deep (read and written a Python call per
    level, they would take the grader past Python's recursion limit)."""
    path = variants.compose('py_correct', tmp_path)
    with open(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'), 'w') as stream:
        stream.write(text)
    assert _includes_world(submission.find(path), tmp_path) == []


def test_includes_are_read_a_bounded_number_of_times(tmp_path, monkeypatch):
    """Five files, each including the next four times: 1365 reads without a bound on the total
    (and 10 files of 10 within the depth limit would be 10**10)."""
    path = variants.compose('py_correct', tmp_path)
    launch = os.path.join(path, 'ball_chaser', 'launch')
    for level in range(5):
        _launch(os.path.join(launch, 'level%d.launch' % level),
                '<include file="$(dirname)/level%d.launch"/>' % (level + 1) * 4)
    _launch(os.path.join(launch, 'ball_chaser.launch'), '<include file="$(dirname)/level0.launch"/>')
    found = submission.find(path)
    reads = []
    original = submission.read_beneath
    monkeypatch.setattr(submission, 'read_beneath', lambda *args: reads.append(args) or original(*args))
    assert _includes_world(found, tmp_path) == []
    assert len(reads) == submission.MAX_INCLUDE_READS


@pytest.mark.parametrize('body', [
    '',
    '<include file="$(find my_robot)/launch/robot_description.launch"/>',
    '<include if="false" file="$(find my_robot)/launch/world.launch"/>',
    '<arg name="sim" default="false"/><include if="$(arg sim)" file="$(find my_robot)/launch/world.launch"/>',
    '<include unless="$(optenv NO_WORLD 0)" file="$(find my_robot)/launch/world.launch"/>',
    '<include file="$(eval find(\'my_robot\') + \'/launch/world.launch\')"/>',
    '<include file="$(find gazebo_ros)/launch/empty_world.launch"/>',
    '<include file="$(dirname)/ball_chaser.launch"/>',
])
def test_a_ball_chaser_launch_that_does_not_surely_start_the_world_is_launched_after_it(tmp_path, body):
    path = variants.compose('py_correct', tmp_path)
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'), body)
    assert _includes_world(submission.find(path), tmp_path) == []


# -- launch files ----------------------------------------------------------------------------

LAUNCH = """<launch>
  <node name="drive_bot" type="drive_bot" pkg="ball_chaser" output="screen"/>
  <group if="true">
    <node name="process_image" type="process_image.py" pkg="ball_chaser"/>
  </group>
  <node name="rviz" pkg="rviz" type="rviz" required="true"/>
</launch>
"""


def _prepared(tmp_path, copies='copies', **kwargs):
    launch = tmp_path / 'pkg' / 'launch' / 'ball_chaser.launch'
    if not launch.exists():
        launch.parent.mkdir(parents=True)
        launch.write_text(LAUNCH)
    changes = headless_launch.prepare_launch_files(str(tmp_path / 'pkg'), str(tmp_path / copies), **kwargs)
    assert launch.read_text() == LAUNCH                   # the package itself is never written
    copy = changes.copies.get(str(launch))
    return changes, ET.parse(copy).getroot() if copy else None


def test_gui_nodes_are_left_out_and_process_image_is_remapped(tmp_path):
    changes, root = _prepared(tmp_path, remap=True)
    assert list(changes.copies.values()) == [str(tmp_path / 'copies' / 'launch' / 'ball_chaser.launch')]
    assert changes.dropped == ['rviz (rviz/rviz)']
    assert changes.remapped == ['process_image (ball_chaser/process_image.py)']
    nodes = {node.get('name'): node for node in root.iter('node')}
    assert set(nodes) == {'drive_bot', 'process_image'}
    assert nodes['drive_bot'].find('remap') is None
    remap = nodes['process_image'].find('remap')
    assert (remap.get('from'), remap.get('to')) == (submission.COURSE_SERVICE, submission.PROXY_SERVICE)


def test_preparing_again_starts_from_the_original(tmp_path):
    _prepared(tmp_path, remap=True)
    changes, root = _prepared(tmp_path, copies='again', remap=True, keep=['process_image'])
    assert changes.remapped == []
    assert not list(root.iter('remap'))


def test_a_launch_file_that_links_elsewhere_is_neither_read_nor_written(tmp_path):
    host = tmp_path / 'host.launch'
    host.write_text(LAUNCH)
    (tmp_path / 'pkg' / 'launch').mkdir(parents=True)
    os.symlink(str(host), str(tmp_path / 'pkg' / 'launch' / 'extra.launch'))
    os.symlink(str(tmp_path), str(tmp_path / 'pkg' / 'linked_folder'))
    changes = headless_launch.prepare_launch_files(str(tmp_path / 'pkg'), str(tmp_path / 'copies'))
    assert changes.copies == {} and changes.dropped == []
    assert host.read_text() == LAUNCH


# -- the world's launch ----------------------------------------------------------------------------

def test_a_world_launch_whose_simulator_died_is_over_though_roslaunch_runs_on(tmp_path):
    """The simulator is the grader's own (grading/simulator.py): the world's launch is over once
    it has ended, whatever roslaunch does."""
    from chase_tools.grading.launches import WorldLaunch
    from chase_tools.procs import ProcessGroup
    launch, simulator = WorldLaunch(stop_timeout=1.0), ProcessGroup(stop_timeout=1.0)
    with open(tmp_path / 'log', 'w') as log:
        launch.start(['sleep', '30'], log)
        simulator.start(['sleep', '30'], log)
    launch.simulator = simulator
    try:
        assert launch.alive() and not launch.simulator_died
        simulator.procs[0].kill()
        simulator.procs[0].wait()
        assert not launch.alive() and launch.simulator_died
    finally:
        launch.stop()
        simulator.stop()


# -- the world, read through the submission's copy --------------------------------------------

CRATE_CONFIG = '<model><name>crate</name><sdf version="1.6">%s</sdf></model>'
CRATE_SDF = ('<sdf version="1.6"><model name="crate"><static>true</static><link name="l"><collision '
             'name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link></model></sdf>')
CRATE_WORLD = ('<sdf version="1.6"><world name="w"><include><uri>model://crate</uri>'
               '<pose>2 0 0 0 0 0</pose></include></world></sdf>')


def test_the_world_and_the_models_it_includes_are_read_through_a_copy(tmp_path, monkeypatch):
    models = tmp_path / 'models' / 'crate'
    models.mkdir(parents=True)
    (models / 'model.config').write_text(CRATE_CONFIG % 'crate.sdf')
    (models / 'crate.sdf').write_text(CRATE_SDF)
    world = tmp_path / 'office.world'
    world.write_text(CRATE_WORLD)
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(models.parent))
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    assert worldcopy.copy(str(world), str(tmp_path / 'run' / 'world')) == []
    taken = worldcopy.snapshot(str(tmp_path / 'run'), 'world', str(tmp_path / 'grader'), str(world))
    assert taken.left_out == [] and taken.world_file == str(tmp_path / 'grader' / 'office.world')
    loaded = load_world(taken.world_file, taken.model_paths)
    assert [(model.name, model.pose.x) for model in loaded.models] == [('crate', 2.0)]


def test_the_graders_snapshot_takes_no_link_no_entity_and_no_file_outside_a_model_folder(tmp_path):
    """What the submission's sandbox left in the copy, read as root: links to a file of the
    grader's, a model.config naming a file outside its folder, entity declarations."""
    secret = tmp_path / 'secret.world'
    secret.write_text(CRATE_WORLD)
    copy = tmp_path / 'run' / 'world'
    (copy / 'models' / 'crate').mkdir(parents=True)
    (copy / 'models' / 'bomb').mkdir()
    os.symlink(str(secret), str(copy / 'office.world'))
    os.symlink(str(tmp_path), str(copy / 'models' / 'linked'))
    (copy / 'models' / 'crate' / 'model.config').write_text(CRATE_CONFIG % '../../../../secret.world')
    (copy / 'models' / 'bomb' / 'model.config').write_text(
        '<!DOCTYPE model [<!ENTITY a "a">]>' + CRATE_CONFIG % 'crate.sdf')
    taken = worldcopy.snapshot(str(tmp_path / 'run'), 'world', str(tmp_path / 'grader'), 'office.world')
    assert taken.world_file == ''
    said = '\n'.join(taken.left_out)
    assert 'world/office.world (Too many levels of symbolic links)' in said, said
    assert 'crate/model.config (names a file outside its folder)' in said, said
    assert 'world/models/bomb/model.config (declares XML entities)' in said, said
    kept = [os.path.join(root, name) for root, dirs, files in os.walk(str(tmp_path / 'grader'))
            for name in dirs + files]
    assert sorted(os.path.relpath(path, str(tmp_path / 'grader')) for path in kept) == [
        'models', 'models/bomb', 'models/crate']


@pytest.mark.parametrize('names', ['.', 'model.config', './', 'sub/..'])
def test_a_model_config_naming_its_folder_or_itself_leaves_the_model_out_with_a_reason(tmp_path, monkeypatch,
                                                                                       names):
    models = tmp_path / 'models' / 'crate'
    models.mkdir(parents=True)
    (models / 'model.config').write_text(CRATE_CONFIG % names)
    (models / 'crate.sdf').write_text(CRATE_SDF)
    world = tmp_path / 'office.world'
    world.write_text(CRATE_WORLD)
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(models.parent))
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    said = worldcopy.copy(str(world), str(tmp_path / 'run' / 'world'))
    assert said == ['%s names %s: not a model file' % (models / 'model.config', os.path.normpath(names))]
    # What the sandbox could have written anyway, read by the grader.
    copied = tmp_path / 'run' / 'world' / 'models' / 'crate' / 'model.config'
    copied.write_text(CRATE_CONFIG % names)
    taken = worldcopy.snapshot(str(tmp_path / 'run'), 'world', str(tmp_path / 'grader'), str(world))
    assert taken.world_file == str(tmp_path / 'grader' / 'office.world')
    assert any('names %s: not a model file' % os.path.normpath(names) in line
               for line in taken.left_out), taken.left_out
    assert load_world(taken.world_file, taken.model_paths).models == []
