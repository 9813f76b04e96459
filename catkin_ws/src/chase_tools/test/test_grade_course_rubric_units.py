"""The course rubric's rows that are not behaviour (grading/course_rubric.py), judged from small
submissions written here from the rubric's words, and how --rubric counts them."""
import json
import os
import types

import pytest

from chase_tools.grading import cli, course_rubric, formats, gather, options, rubric, submission
from session_fakes import DescriptionMaster

# The lesson's sample robot, as the lessons build it: a .4 x .2 x .1 chassis with two casters,
# two wheels of radius .1 on continuous joints, no colour, the differential drive plugin.
SAMPLE_URDF = """<?xml version="1.0"?>
<robot name="my_robot">
  <gazebo>
    <plugin name="differential_drive_controller" filename="libgazebo_ros_diff_drive.so">
      <leftJoint>left_wheel_hinge</leftJoint><rightJoint>right_wheel_hinge</rightJoint>
    </plugin>
  </gazebo>
  <link name="robot_footprint"/>
  <joint name="robot_footprint_joint" type="fixed">
    <origin xyz="0 0 0" rpy="0 0 0"/><parent link="robot_footprint"/><child link="chassis"/>
  </joint>
  <link name="chassis">
    <inertial><mass value="15.0"/><origin xyz="0 0 0" rpy="0 0 0"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision name="collision"><origin xyz="0 0 0" rpy="0 0 0"/>
      <geometry><box size=".4 .2 .1"/></geometry></collision>
    <visual name="chassis_visual"><origin xyz="0 0 0" rpy="0 0 0"/>
      <geometry><box size=".4 .2 .1"/></geometry></visual>
  </link>
  WHEELS
</robot>
"""
WHEEL = """
  <link name="{side}_wheel">
    <inertial><mass value="5"/><origin xyz="0 0 0" rpy="0 1.5707 1.5707"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision name="{side}_wheel_collision"><origin xyz="0 0 0" rpy="0 1.5707 1.5707"/>
      <geometry><cylinder radius="{radius}" length="0.05"/></geometry></collision>
    <visual name="{side}_wheel_visual"><origin xyz="0 0 0" rpy="0 1.5707 1.5707"/>
      <geometry><cylinder radius="{radius}" length="0.05"/></geometry></visual>
  </link>
  <joint type="continuous" name="{side}_wheel_hinge">
    <origin xyz="{x} {y} 0" rpy="0 0 0"/><child link="{side}_wheel"/><parent link="chassis"/>
    <axis xyz="0 1 0" rpy="0 0 0"/>
  </joint>"""


def robot_urdf(sides=(('left', 0, 0.15), ('right', 0, -0.15)), radius='0.1', chassis='.4 .2 .1',
               extra=''):
    wheels = ''.join(WHEEL.format(side=side, x=x, y=y, radius=radius) for side, x, y in sides)
    return SAMPLE_URDF.replace('WHEELS', wheels + extra).replace('.4 .2 .1', chassis)


BLUE_CHASSIS = '<gazebo reference="chassis"><material>Gazebo/Blue</material></gazebo>'
SKID_STEER = """<gazebo><plugin name="skid_steer_drive_controller"
  filename="libgazebo_ros_skid_steer_drive.so"><leftFrontJoint>front_left_wheel_hinge</leftFrontJoint>
  </plugin></gazebo>"""
FOUR_WHEELS = (('front_left', 0.15, 0.15), ('front_right', 0.15, -0.15),
               ('back_left', -0.15, 0.15), ('back_right', -0.15, -0.15))


# -- robot_differs_from_sample --------------------------------------------------------------

def test_the_lessons_sample_robot_fails_and_says_what_is_the_samples():
    passed, evidence, judged = course_rubric.differs_from_sample(robot_urdf())
    assert judged and not passed
    assert evidence.startswith("the spawned robot is the lesson's sample in chassis `chassis` "
                               "0.4 x 0.2 x 0.1 m, as the sample's; 2 wheels of radius 0.1 m")
    assert 'changed: nothing' in evidence


def test_a_robot_changed_in_colour_wheels_and_chassis_passes_with_each_change_named():
    urdf = robot_urdf(radius='0.15', chassis='.5 .3 .1', extra=BLUE_CHASSIS)
    passed, evidence, judged = course_rubric.differs_from_sample(urdf)
    assert judged and passed
    assert evidence == ("the spawned robot differs from the lesson's sample: chassis `chassis` "
                        "0.5 x 0.3 x 0.1 m (sample 0.4 x 0.2 x 0.1 m); 2 wheels of radius 0.15 m "
                        "(sample 0.1 m); colour: chassis Gazebo/Blue")


def test_a_robot_changed_in_colour_and_chassis_only_fails_for_its_wheels():
    """The rubric's minimum changes are all three: colour, wheel radius and chassis size."""
    urdf = robot_urdf(chassis='.6 .3 .2', extra=BLUE_CHASSIS)
    passed, evidence, _ = course_rubric.differs_from_sample(urdf)
    assert not passed
    assert "2 wheels of radius 0.1 m, as the sample's" in evidence
    assert 'changed: chassis `chassis` 0.6 x 0.3 x 0.2 m' in evidence


def test_a_white_material_is_the_samples_colour():
    white = '<gazebo reference="chassis"><material>Gazebo/White</material></gazebo>'
    passed, evidence, _ = course_rubric.differs_from_sample(
        robot_urdf(radius='0.2', chassis='.5 .3 .1', extra=white))
    assert not passed and 'no colour but white' in evidence


# -- skid_steer -----------------------------------------------------------------------------

def test_a_skid_steer_robot_stands_out_and_a_differential_drive_does_not():
    skid = robot_urdf(sides=FOUR_WHEELS, extra=SKID_STEER)
    assert course_rubric.skid_steer(skid) == (
        True, 'the spawned robot uses the skid steer drive plugin (libgazebo_ros_skid_steer_drive.so)',
        True)
    passed, evidence, judged = course_rubric.skid_steer(robot_urdf())
    assert judged and not passed
    assert evidence == ('the spawned robot is not skid steer: drive plugin '
                        'libgazebo_ros_diff_drive.so, 2 wheels')


# -- course_layout, cpp_nodes, ball_any_colour, building_editor_world from the files --------

PACKAGE_XML = ('<package format="2"><name>%s</name><version>0.0.0</version><description>d'
               '</description><maintainer email="a@b.c">a</maintainer><license>BSD</license>'
               '<buildtool_depend>catkin</buildtool_depend></package>')
CPP_CMAKE = """cmake_minimum_required(VERSION 2.8.3)
project(ball_chaser)
# add_executable(old_node src/old.py)
add_executable(drive_bot src/drive_bot.cpp)
add_executable(process_image src/process_image.cpp)
"""
PY_CMAKE = """cmake_minimum_required(VERSION 2.8.3)
project(ball_chaser)
catkin_install_python(PROGRAMS scripts/drive_bot.py scripts/process_image.py
  DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
"""
WHITE_ONLY = """void process_image_callback(const sensor_msgs::Image img)
{
    int white_pixel = 255;
    for (int i = 0; i + 2 < img.height * img.step; i += 3) {
        if (img.data[i] == white_pixel && img.data[i + 1] == 255 && img.data[i + 2] == 255) {
"""
RED_BALL = """void process_image_callback(const sensor_msgs::Image img)
{
    for (int i = 0; i + 2 < img.height * img.step; i += 3) {
        if (img.data[i] > 200 && img.data[i + 1] < 60 && img.data[i + 2] < 60) {
"""


def write(path, text=''):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def a_submission(top, cpp=True, colour_test=WHITE_ONLY, world='', robot='my_robot', models=()):
    """A submission laid out as the project description shows it; the parts as asked."""
    write(top / robot / 'package.xml', PACKAGE_XML % robot)
    write(top / robot / 'CMakeLists.txt', 'project(%s)\n' % robot)
    write(top / robot / 'launch' / 'world.launch', '<launch/>')
    write(top / robot / 'urdf' / 'my_robot.xacro', robot_urdf())
    write(top / robot / 'worlds' / 'my.world', world or HAND_WRITTEN_WORLD)
    for name, text in models:
        write(top / robot / 'models' / name / 'model.sdf', text)
        write(top / robot / 'models' / name / 'model.config', '<model><sdf>model.sdf</sdf></model>')
    chaser = top / 'ball_chaser'
    write(chaser / 'package.xml', PACKAGE_XML % 'ball_chaser')
    write(chaser / 'launch' / 'ball_chaser.launch', '<launch/>')
    write(chaser / 'srv' / 'DriveToTarget.srv', 'float64 linear_x\nfloat64 angular_z\n---\nstring msg_feedback\n')
    if cpp:
        write(chaser / 'CMakeLists.txt', CPP_CMAKE)
        write(chaser / 'src' / 'drive_bot.cpp', 'int main() {}\n')
        write(chaser / 'src' / 'process_image.cpp', colour_test)
    else:
        write(chaser / 'CMakeLists.txt', PY_CMAKE)
        write(chaser / 'scripts' / 'drive_bot.py', 'import rospy\n')
        write(chaser / 'scripts' / 'process_image.py', 'if r == 255 and g == 255 and b == 255:\n')
    return submission.find(str(top))


def wall(index, x, y, yaw, length):
    return """
      <link name='Wall_{i}'>
        <collision name='Wall_{i}_Collision'>
          <geometry><box><size>{length} 0.15 2.5</size></box></geometry>
          <pose>0 0 1.25 0 -0 0</pose>
        </collision>
        <visual name='Wall_{i}_Visual'>
          <pose>0 0 1.25 0 -0 0</pose>
          <geometry><box><size>{length} 0.15 2.5</size></box></geometry>
          <meta><layer>0</layer></meta>
        </visual>
        <pose>{x} {y} 0 0 -0 {yaw}</pose>
      </link>""".format(i=index, x=x, y=y, yaw=yaw, length=length)


# Four walls of a 6 m room round the origin, as Gazebo's Building Editor saves them.
BUILDING = """<model name='my_building'>
      <pose>0 0 0 0 -0 0</pose>%s
      <static>1</static>
    </model>""" % ''.join(wall(i, x, y, yaw, 6.15) for i, (x, y, yaw) in enumerate(
    [(0, 3, 0), (3, 0, -1.5708), (0, -3, 3.14159), (-3, 0, 1.5708)]))
BALL = """<model name='my_ball'><pose>1 0 0.1 0 0 0</pose><link name='link'>
      <collision name='c'><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
      <visual name='v'><geometry><sphere><radius>0.1</radius></sphere></geometry>
        <material><ambient>1 1 1 1</ambient><diffuse>1 1 1 1</diffuse></material></visual>
    </link></model>"""
BOX = """<model name='box_1'><static>1</static><pose>4 4 0.5 0 0 0</pose><link name='link'>
      <collision name='collision'><geometry><box><size>1 1 1</size></box></geometry></collision>
      <visual name='visual'><geometry><box><size>1 1 1</size></box></geometry></visual>
    </link></model>"""


def world_of(*models, includes=()):
    return ("<?xml version='1.0'?>\n<sdf version='1.6'><world name='default'>%s%s</world></sdf>\n"
            % (''.join(models), ''.join('<include><uri>model://%s</uri></include>' % name
                                        for name in includes)))


BUILDING_EDITOR_WORLD = world_of(BUILDING, BALL)
HAND_WRITTEN_WORLD = world_of(BOX, BALL)


def test_a_submission_in_the_courses_layout_passes_and_a_missing_srv_fails(tmp_path):
    found = a_submission(tmp_path)
    assert course_rubric.file_rows(found)['course_layout'] == (
        True, 'my_robot has launch/, urdf/, worlds/; ball_chaser has launch/, src/, srv/DriveToTarget.srv',
        True)
    os.remove(tmp_path / 'ball_chaser' / 'srv' / 'DriveToTarget.srv')
    passed, evidence, judged = course_rubric.file_rows(submission.find(str(tmp_path)))['course_layout']
    assert judged and not passed
    assert evidence == "missing from the course's layout: ball_chaser/srv/DriveToTarget.srv"


def test_cpp_nodes_pass_and_python_nodes_fail_saying_so(tmp_path):
    cpp = a_submission(tmp_path / 'cpp')
    assert course_rubric.file_rows(cpp)['cpp_nodes'] == (
        True, 'CMakeLists.txt builds C++ nodes: drive_bot from src/drive_bot.cpp; process_image from '
              'src/process_image.cpp', True)
    python = a_submission(tmp_path / 'py', cpp=False)
    assert course_rubric.file_rows(python)['cpp_nodes'] == (
        False, 'drive_bot and process_image are Python (scripts/drive_bot.py, scripts/process_image.py); '
               'the course asks for C++ nodes', True)


def test_a_white_only_colour_test_fails_a_red_one_passes_and_an_unclear_one_is_not_judged(tmp_path):
    white = course_rubric.file_rows(a_submission(tmp_path / 'white'))['ball_any_colour']
    assert white[0] is False and white[2] is True
    assert white[1].startswith('process_image looks for white only: `int white_pixel = 255;` '
                               '(src/process_image.cpp:3)')
    red = course_rubric.file_rows(a_submission(tmp_path / 'red', colour_test=RED_BALL))['ball_any_colour']
    assert red == (True, 'process_image tests a colour other than white: `if (img.data[i] > 200 && '
                         'img.data[i + 1] < 60 && img.data[i + 2] < 60) {` (src/process_image.cpp:4)', True)
    unclear = course_rubric.file_rows(a_submission(tmp_path / 'unclear', colour_test='int main() {}\n'))
    assert unclear['ball_any_colour'] == (
        False, 'not judged: the colour test of src/process_image.cpp could not be read plainly from '
               'its source', False)


def test_an_hsv_colour_test_passes_and_a_count_below_a_level_is_no_colour_test(tmp_path):
    hsv = 'cv::cvtColor(image, hsv_image, cv::COLOR_BGR2HSV);\n'
    found = a_submission(tmp_path / 'hsv', colour_test=hsv)
    assert course_rubric.file_rows(found)['ball_any_colour'][0] is True
    counted = WHITE_ONLY + '    if (counts[0] < 10) { return; }\n'
    found = a_submission(tmp_path / 'counted', colour_test=counted)
    passed, evidence, judged = course_rubric.file_rows(found)['ball_any_colour']
    assert judged and not passed and evidence.startswith('process_image looks for white only')


def test_a_building_editor_world_passes_and_a_hand_written_box_world_fails(tmp_path):
    built = course_rubric.file_rows(a_submission(tmp_path / 'b', world=BUILDING_EDITOR_WORLD))
    assert built['building_editor_world'] == (
        True, 'the world worlds/my.world holds `my_building`, saved by the Building Editor (4 walls) '
              '(read from the files: the launched world was not seen)', True)
    boxed = course_rubric.file_rows(a_submission(tmp_path / 'h'))
    assert boxed['building_editor_world'] == (
        False, "no model of the world worlds/my.world has the Building Editor's walls (links Wall_N "
               "with Wall_N_Collision, Wall_N_Visual); its models: box_1, my_ball", True)


def test_a_building_included_from_a_model_folder_the_editor_saved_passes(tmp_path):
    model = "<?xml version='1.0'?>\n<sdf version='1.6'>%s</sdf>\n" % BUILDING
    found = a_submission(tmp_path, world=world_of(BALL, includes=['my_building']),
                         models=[('my_building', model)])
    passed, evidence, _ = course_rubric.file_rows(found)['building_editor_world']
    assert passed and evidence.startswith('the world worlds/my.world includes model://my_building, a '
                                          'model folder saved by the Building Editor (4 walls)')


def test_skid_steer_is_read_from_the_robot_files_when_no_robot_was_spawned(tmp_path):
    found = a_submission(tmp_path)
    assert course_rubric.file_rows(found)['skid_steer'][:2] == (
        False, 'no robot description of the robot package names libgazebo_ros_skid_steer_drive.so '
               '(read from its files)')
    write(tmp_path / 'my_robot' / 'urdf' / 'my_robot.gazebo', SKID_STEER)
    assert course_rubric.file_rows(found)['skid_steer'] == (
        True, 'urdf/my_robot.gazebo names the skid steer drive plugin (libgazebo_ros_skid_steer_drive.so)',
        True)


# -- what the run saw: the spawned robot, the spawn point, the world launched ----------------

def a_run(tmp_path, monkeypatch, world, x, y, urdf):
    """The rubric run's session after the world came up: the robot spawned at (x, y)."""
    from chase_tools.grading.session import Session, SessionSpec
    monkeypatch.setattr(os, 'environ', dict(os.environ))      # the session sets ROS's variables
    spec = SessionSpec(overlay_env={}, overlay_root=str(tmp_path), run_scratch=str(tmp_path / 'run'),
                       out_dir=str(tmp_path / 'out'), robot_package='my_robot',
                       chaser_package='ball_chaser', isolate=False)
    session = Session(spec)
    world_file = tmp_path / 'my.world'
    world_file.write_text(world)
    session.found.world_file, session.found.model_paths = str(world_file), []
    session.found.robot, session.found.ball = 'my_robot', 'my_ball'
    session.found.spawn_pose = types.SimpleNamespace(x=x, y=y)
    session.master = DescriptionMaster({'/robot_description': urdf})
    session.judge_course_rows()
    return session.grade


def test_a_robot_spawned_inside_the_buildings_walls_is_housed(tmp_path, monkeypatch):
    grade = a_run(tmp_path, monkeypatch, BUILDING_EDITOR_WORLD, 0.0, 0.0,
                  robot_urdf(sides=FOUR_WHEELS, radius='0.12', chassis='.5 .3 .1',
                             extra=BLUE_CHASSIS + SKID_STEER))
    housed = grade.row('robot_housed_in_world')
    assert (housed.verdict, housed.evidence) == (
        rubric.PASS, "spawned at (0.00, 0.00), inside the world's walls: rays in all 16 directions "
                     "meet a collider")
    assert grade.row('robot_differs_from_sample').verdict == rubric.PASS
    assert grade.row('robot_differs_from_sample').evidence.startswith(
        "the spawned robot `my_robot` differs from the lesson's sample: chassis `chassis` 0.5 x 0.3")
    assert grade.row('skid_steer').verdict == rubric.PASS
    assert grade.row('building_editor_world').evidence == (
        'the world my.world holds `my_building`, saved by the Building Editor (4 walls)')


def test_a_robot_spawned_outside_the_walls_is_not_housed(tmp_path, monkeypatch):
    grade = a_run(tmp_path, monkeypatch, BUILDING_EDITOR_WORLD, 8.0, 0.0, robot_urdf())
    housed = grade.row('robot_housed_in_world')
    assert (housed.verdict, housed.evidence) == (
        rubric.FAIL, 'spawned at (8.00, 0.00), outside any building: a ray from there meets no wall')
    assert grade.row('robot_differs_from_sample').verdict == rubric.FAIL
    assert grade.row('skid_steer').verdict == rubric.FAIL


def test_a_run_with_no_robot_description_leaves_the_robot_not_judged(tmp_path, monkeypatch):
    grade = a_run(tmp_path, monkeypatch, HAND_WRITTEN_WORLD, 0.0, 0.0, None)
    row = grade.row('robot_differs_from_sample')
    assert row.verdict == rubric.UNJUDGED
    assert row.evidence == ('not judged: no robot_description parameter holds the URDF of the '
                            'spawned robot `my_robot`')
    assert grade.row('building_editor_world').verdict == rubric.FAIL


# -- --rubric: which rows count -------------------------------------------------------------

def a_grade(counted=rubric.ROW_NAMES):
    grade = rubric.Grade('/subs/alice')
    for name in rubric.ITEM_NAMES:
        grade.set(name, True, 'evidence of %s' % name)
    grade.counted_rows = list(counted)
    for name in rubric.ROW_NAMES:
        grade.set_row(name, name in ('course_layout', 'cpp_nodes', 'skid_steer'), 'seen for %s' % name)
    grade.set_row('robot_housed_in_world', False, 'not judged: the robot was not spawned', False)
    return grade


def test_rubric_chooses_the_rows_counted_and_the_report_marks_the_others(tmp_path):
    args = cli.parse_args([str(tmp_path), '--rubric', 'cpp_nodes, course_layout,building_editor_world'])
    assert args.rubric == ('course_layout', 'building_editor_world', 'cpp_nodes')
    assert cli.parse_args([str(tmp_path)]).rubric == rubric.ROW_NAMES
    grade = a_grade(args.rubric)
    text = rubric.markdown(grade)
    assert 'Course rubric rows counted (3): 2 passed, 1 failed, 0 not judged.' in text.splitlines()
    assert "## The course's other rubric rows" in text
    assert ('| `cpp_nodes` | drive_bot and process_image are C++ nodes | PASS | seen for cpp_nodes |'
            in text.splitlines())
    assert ('| `skid_steer` | stand out: a skid-steer robot design | PASS (not counted) | seen for '
            'skid_steer |' in text.splitlines())
    assert text.index('| `chase` |') < text.index("The course's other rubric rows")
    every = rubric.markdown(a_grade())
    assert ('Course rubric rows counted (5): 2 passed, 2 failed, 1 not judged; stand out: 1 of 2.'
            in every.splitlines())


def test_an_unknown_rubric_row_is_a_clear_error(tmp_path, capsys):
    with pytest.raises(SystemExit):
        cli.parse_args([str(tmp_path), '--rubric', 'cpp_nodes,colour'])
    assert 'unknown rubric row colour; the rows are course_layout' in capsys.readouterr().err


def test_the_rows_go_to_grade_json_gradescope_and_the_class_csv(tmp_path):
    grade = a_grade(('cpp_nodes', 'skid_steer', 'robot_housed_in_world'))
    rubric.write_json(grade, str(tmp_path / 'grade.json'))
    data = json.loads((tmp_path / 'grade.json').read_text())
    assert [row['name'] for row in data['course_rows']] == list(rubric.ROW_NAMES)
    assert data['course_rows'][4] == {'name': 'cpp_nodes', 'passed': True, 'judged': True,
                                      'evidence': 'seen for cpp_nodes', 'counted': True}
    assert [len(data['items']), data['items'][0]['name']] == [7, 'builds']
    again = rubric.Grade.from_json(data)
    assert again.counted_rows == ['robot_housed_in_world', 'cpp_nodes', 'skid_steer']
    assert again.row('robot_housed_in_world').verdict == rubric.UNJUDGED
    scope = formats.gradescope(grade)
    tests = {test['name']: test for test in scope['tests']}
    assert len(scope['tests']) == 7 + 7
    assert (tests['cpp_nodes']['score'], tests['cpp_nodes']['max_score']) == (1.0, 1.0)
    assert (tests['skid_steer']['score'], tests['skid_steer']['max_score']) == (1.0, 0.0)   # extra credit
    assert tests['course_layout']['max_score'] == 0.0 and 'not counted' in tests['course_layout']['tags']
    assert tests['robot_housed_in_world']['extra_data'] == {'verdict': rubric.UNJUDGED}
    assert scope['score'] == 7 + 1 + 1
    row = gather.csv_row(gather.Row('alice', grade))
    values = dict(zip(gather.CSV_COLUMNS, row))
    assert (values['cpp_nodes'], values['course_layout']) == ('pass', 'pass (not counted)')


def test_the_class_grade_passes_the_rows_counted_on(tmp_path):
    (tmp_path / 'alice').mkdir()
    args = cli.parse_args([str(tmp_path), '--rubric', 'skid_steer,cpp_nodes'])
    forwarded = options.submission_args(args)
    assert forwarded[forwarded.index('--rubric') + 1] == 'cpp_nodes,skid_steer'
    again = cli.parse_args([str(tmp_path / 'alice')] + forwarded)
    assert again.rubric == ('cpp_nodes', 'skid_steer')
    none = cli.parse_args([str(tmp_path), '--rubric', ','])
    assert cli.parse_args([str(tmp_path / 'alice')] + options.submission_args(none)).rubric == ()


def test_teaching_md_lists_every_rubric_row_with_how_it_is_judged():
    top = os.path.realpath(os.path.join(os.path.dirname(__file__), '..', '..', '..', '..'))
    with open(os.path.join(top, 'docs', 'teaching.md'), encoding='utf-8') as stream:
        text = stream.read()
    section = text[text.index("### The course's whole rubric"):]
    section = section[:section.index('\n### ', 1)]
    judged_by = [line.split(' | ')[1] for line in section.splitlines() if line.startswith('| ')]
    for name in rubric.ITEM_NAMES + rubric.ROW_NAMES:
        assert any('`%s`' % name in cell for cell in judged_by), name
    # Each row that is not behaviour says when it passes, fails and is not judged.
    rows = [line for line in section.splitlines() if line.startswith('| `')]
    assert sorted(line.split('`')[1] for line in rows) == sorted(rubric.ROW_NAMES)
    assert all(line.count(' | ') == 3 for line in rows)
    assert '--rubric ROWS' in section and '[--rubric ROWS]' in text
