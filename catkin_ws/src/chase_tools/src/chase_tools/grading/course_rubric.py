"""The course rubric's rows that are not behaviour (rubric.COURSE_ROWS), judged as a reviewer
would, from the submission's files and what the run saw. Pure: no ROS.

Each judge returns (passed, evidence, judged): evidence's first words say what was seen; a row
that cannot be judged says "not judged: why".

  course_layout              the project description's folders and files (file_rows)
  robot_differs_from_sample  the spawned robot's URDF (xacro already run) against the lesson's
                             sample: colour, wheel radius and chassis dimensions (robot_rows)
  robot_housed_in_world      the spawn point lies within colliders on every side (housed)
  building_editor_world      a model of the world, or one it includes from a model folder, has
                             the Building Editor's walls (building_editor)
  cpp_nodes                  ball_chaser's CMakeLists.txt builds drive_bot and process_image
                             from C++ sources (cpp_nodes)
  skid_steer                 the robot uses the skid steer drive plugin, or drives four wheels
                             through ros_control (robot_rows; from the robot package's text
                             when no URDF was spawned)
  ball_any_colour            process_image's colour test, when the source shows it plainly
                             (ball_colour)

The rows the run decides start as not judged (file_rows) and the session's world_check
replaces them with what it saw (submission_grade.run_session).
"""
import os
import re
import stat
import xml.etree.ElementTree as ET

from chase_tools.grading import submission
from chase_tools.grading.rubric import NOT_JUDGED, ROW_NAMES
from chase_tools.grading.scratch import read_beneath

# The lesson's sample robot (my_robot.xacro as the lessons build it): a .4 x .2 x .1 box chassis,
# wheels of radius .1, and no colour of its own (Gazebo draws it in its default white-grey).
SAMPLE_CHASSIS_M = (0.4, 0.2, 0.1)
SAMPLE_WHEEL_RADIUS_M = 0.1
# Sizes closer than this are the sample's.
SIZE_TOLERANCE_M = 1e-3
# A colour at least this light in every channel reads as the sample's white.
WHITE_LEVEL = 0.95
WHITE_NAMES = ('gazebo/white', 'white')
SKID_STEER_PLUGIN = 'libgazebo_ros_skid_steer_drive.so'
# The Building Editor names each part of a building it saves: Wall_0, Door_1, Window_2, ...
BUILDING_PART = re.compile(r'^(Wall|Door|Window|Stairs|Floor)_\d+$')
CPP_SOURCE = re.compile(r'\.(cpp|cc|cxx|c\+\+|C)$')
NODES = ('drive_bot', 'process_image')
SHOWN = 4
ROBOT_FILES = ('.xacro', '.urdf', '.gazebo', '.sdf')


def _shown(names):
    names = list(names)
    return ', '.join(names[:SHOWN]) + (' and %d more' % (len(names) - SHOWN) if len(names) > SHOWN else '')


def _sizes(text):
    try:
        return tuple(float(part) for part in text.split())
    except (AttributeError, ValueError):
        return None


# --- robot_differs_from_sample and skid_steer, from the spawned robot's URDF ----------------

def _geometry(link, kind):
    """The first geometry of kind ('box', 'cylinder') of a link's collisions, else visuals."""
    for tag in ('collision', 'visual'):
        for element in link.findall(tag):
            shape = element.find('geometry/%s' % kind)
            if shape is not None:
                return shape
    return None


def _box_size(link):
    box = _geometry(link, 'box')
    return _sizes(box.get('size')) if box is not None else None


def _colour(robot, link_name, materials):
    """How the robot colours the link: 'Gazebo/Blue', 'rgba 0 0 1 1', or None (no colour: the
    sample's)."""
    for gazebo in robot.findall('gazebo'):
        if gazebo.get('reference') == link_name:
            material = gazebo.find('material')
            if material is not None and (material.text or '').strip():
                return material.text.strip()
    link = next((link for link in robot.findall('link') if link.get('name') == link_name), None)
    for visual in link.findall('visual') if link is not None else ():
        material = visual.find('material')
        if material is None:
            continue
        colour = material.find('color')
        rgba = colour.get('rgba') if colour is not None else materials.get(material.get('name'))
        if rgba:
            return 'rgba %s' % ' '.join(rgba.split())
        if material.get('name'):
            return material.get('name')
    return None


def _is_white(colour):
    if colour.lower() in WHITE_NAMES:
        return True
    values = _sizes(colour[5:]) if colour.startswith('rgba ') else None
    return bool(values) and len(values) >= 3 and all(value >= WHITE_LEVEL for value in values[:3])


def _has_geometry(link):
    return link.find('collision/geometry') is not None or link.find('visual/geometry') is not None


def _chassis(robot):
    """(name, link) of the chassis: the link named chassis, else the robot's root link, or the
    first link fixed to it that has a shape (a robot_footprint has none)."""
    links = {link.get('name'): link for link in robot.findall('link')}
    if 'chassis' in links:
        return 'chassis', links['chassis']
    fixed, children = {}, set()
    for joint in robot.findall('joint'):
        parent, child = joint.find('parent'), joint.find('child')
        if parent is None or child is None:
            continue
        children.add(child.get('link'))
        if joint.get('type') == 'fixed':
            fixed.setdefault(parent.get('link'), []).append(child.get('link'))
    roots = [name for name in links if name not in children]
    seen, queue = set(), roots[:1]
    while queue:
        name = queue.pop(0)
        if name in seen or name not in links:
            continue
        seen.add(name)
        if _has_geometry(links[name]):
            return name, links[name]
        queue += fixed.get(name, [])
    return None, None


def _wheels(robot):
    """{link: radius, or None for a shape that is not a cylinder} of the links continuous joints
    turn."""
    links = {link.get('name'): link for link in robot.findall('link')}
    wheels = {}
    for joint in robot.findall('joint'):
        child = joint.find('child')
        if joint.get('type') != 'continuous' or child is None or child.get('link') not in links:
            continue
        cylinder = _geometry(links[child.get('link')], 'cylinder')
        radius = _sizes(cylinder.get('radius')) if cylinder is not None else None
        wheels[child.get('link')] = radius[0] if radius else None
    return wheels


def _size_text(size):
    return ' x '.join('%g' % value for value in size)


def differs_from_sample(urdf, source='the spawned robot'):
    """(passed, evidence, judged) of robot_differs_from_sample: the rubric's minimum changes are
    all three of colour, wheel radius and chassis dimensions."""
    try:
        robot = ET.fromstring(urdf)
    except ET.ParseError as error:
        return False, NOT_JUDGED + '%s is not XML: %s' % (source, error), False
    materials = {material.get('name'): material.find('color').get('rgba')
                 for material in robot.findall('material')
                 if material.get('name') and material.find('color') is not None}
    chassis_name, chassis = _chassis(robot)
    wheels = _wheels(robot)
    changed, same = [], []
    if chassis is None:
        changed.append('chassis: no box link (not the sample\'s %s m box)' % _size_text(SAMPLE_CHASSIS_M))
    else:
        size = _box_size(chassis)
        if size is None or len(size) != 3:
            changed.append('chassis `%s`: not a box (the sample\'s is a %s m box)'
                           % (chassis_name, _size_text(SAMPLE_CHASSIS_M)))
        elif all(abs(a - b) < SIZE_TOLERANCE_M for a, b in zip(size, SAMPLE_CHASSIS_M)):
            same.append('chassis `%s` %s m, as the sample\'s' % (chassis_name, _size_text(size)))
        else:
            changed.append('chassis `%s` %s m (sample %s m)' % (chassis_name, _size_text(size),
                                                             _size_text(SAMPLE_CHASSIS_M)))
    round_wheels = {name: radius for name, radius in wheels.items() if radius is not None}
    if not wheels:
        changed.append('wheels: no link turned by a continuous joint (the sample\'s are cylinders '
                       'of radius %g m)' % SAMPLE_WHEEL_RADIUS_M)
    elif not round_wheels:
        changed.append('wheels %s: not cylinders (the sample\'s have radius %g m)'
                       % (_shown(sorted(wheels)), SAMPLE_WHEEL_RADIUS_M))
    else:
        radii = sorted({round(radius, 4) for radius in round_wheels.values()})
        text = '%d wheel%s of radius %s m' % (len(round_wheels), '' if len(round_wheels) == 1 else 's',
                                             ', '.join('%g' % radius for radius in radii))
        if all(abs(radius - SAMPLE_WHEEL_RADIUS_M) < SIZE_TOLERANCE_M for radius in radii):
            same.append('%s, as the sample\'s' % text)
        else:
            changed.append('%s (sample %g m)' % (text, SAMPLE_WHEEL_RADIUS_M))
    coloured = {}
    for name in ([chassis_name] if chassis_name else []) + sorted(wheels):
        colour = _colour(robot, name, materials)
        if colour is not None and not _is_white(colour):
            coloured[name] = colour
    if coloured:
        changed.append('colour: %s' % _shown('%s %s' % (name, colour) for name, colour in coloured.items()))
    else:
        same.append('no colour but white on the chassis and wheels, as the sample (Gazebo\'s default)')
    if same:
        return False, ('%s is the lesson\'s sample in %s; changed: %s (the rubric asks for colour, '
                       'wheel radius and chassis dimensions all changed)'
                       % (source, '; '.join(same), '; '.join(changed) or 'nothing')), True
    return True, '%s differs from the lesson\'s sample: %s' % (source, '; '.join(changed)), True


def skid_steer(urdf, source='the spawned robot'):
    """(passed, evidence, judged): the skid steer drive plugin, or four wheels driven."""
    try:
        robot = ET.fromstring(urdf)
    except ET.ParseError as error:
        return False, NOT_JUDGED + '%s is not XML: %s' % (source, error), False
    plugins = [plugin.get('filename', '') for plugin in robot.iter('plugin')]
    if any(SKID_STEER_PLUGIN in name for name in plugins):
        return True, '%s uses the skid steer drive plugin (%s)' % (source, SKID_STEER_PLUGIN), True
    driven = [transmission for transmission in robot.iter('transmission')]
    if len(driven) >= 4:
        return True, '%s drives %d wheels through ros_control transmissions' % (source, len(driven)), True
    drives = [os.path.basename(name) for name in plugins if 'drive' in name or 'move' in name]
    return False, ('%s is not skid steer: %s, %d wheel%s'
                   % (source, 'drive plugin %s' % _shown(drives) if drives else 'no drive plugin',
                      len(_wheels(robot)), '' if len(_wheels(robot)) == 1 else 's')), True


def robot_rows(urdf, source='the spawned robot'):
    """{row: (passed, evidence, judged)} of the rows the robot's URDF decides."""
    return {'robot_differs_from_sample': differs_from_sample(urdf, source),
            'skid_steer': skid_steer(urdf, source)}


# --- robot_housed_in_world ---------------------------------------------------------------

def housed(x, y, enclosed, rays):
    """(passed, evidence, judged): the spawn point (x, y) enclosed by the world's colliders."""
    if enclosed:
        return True, ('spawned at (%.2f, %.2f), inside the world\'s walls: rays in all %d '
                      'directions meet a collider' % (x, y, rays)), True
    return False, ('spawned at (%.2f, %.2f), outside any building: a ray from there meets no wall'
                   % (x, y)), True


# --- building_editor_world -----------------------------------------------------------------

def _building_parts(model):
    """The names of a model's links saved by the Building Editor: Wall_3 with Wall_3_Collision
    and Wall_3_Visual."""
    parts = []
    for link in model.findall('link'):
        name = link.get('name', '')
        if not BUILDING_PART.match(name):
            continue
        if (any(c.get('name') == name + '_Collision' for c in link.findall('collision'))
                or any(v.get('name') == name + '_Visual' for v in link.findall('visual'))):
            parts.append(name)
    return parts


def _building(model):
    """The text of a model that the Building Editor saved (walls among its parts), else ''."""
    parts = _building_parts(model)
    walls = [part for part in parts if part.startswith('Wall_')]
    if not walls:
        return ''
    counts = {}
    for part in parts:
        kind = part.split('_')[0].lower()
        counts[kind] = counts.get(kind, 0) + 1
    return ', '.join('%d %s%s' % (count, kind, '' if count == 1 else 's') for kind, count in counts.items())


def building_editor(world_text, world_name, model_text):
    """(passed, evidence, judged) for a world's text; model_text(name) is the model.sdf text of
    model://name from the submission's model folders, or None."""
    try:
        root = ET.fromstring(world_text)
    except ET.ParseError as error:
        return False, NOT_JUDGED + 'the world %s is not XML: %s' % (world_name, error), False
    world = root.find('world') if root.tag != 'world' else root
    if world is None:
        return False, 'the world %s holds no <world>' % world_name, True
    names = []
    for model in world.findall('model'):
        names.append(model.get('name', '?'))
        for one in [model] + model.findall('model'):
            parts = _building(one)
            if parts:
                return True, ('the world %s holds `%s`, saved by the Building Editor (%s)'
                              % (world_name, one.get('name', '?'), parts)), True
    for include in world.findall('include'):
        uri = (include.findtext('uri') or '').strip()
        if not uri.startswith('model://'):
            continue
        name = uri[len('model://'):].strip('/').split('/')[0]
        names.append(uri)
        text = model_text(name)
        if text is None:
            continue
        try:
            model_root = ET.fromstring(text)
        except ET.ParseError:
            continue
        for model in model_root.iter('model'):
            parts = _building(model)
            if parts:
                return True, ('the world %s includes %s, a model folder saved by the Building Editor '
                              '(%s)' % (world_name, uri, parts)), True
    return False, ('no model of the world %s has the Building Editor\'s walls (links Wall_N with '
                   'Wall_N_Collision, Wall_N_Visual); its models: %s'
                   % (world_name, _shown(names) or 'none')), True


# --- the submission's files ----------------------------------------------------------------

def _files(top, limit=2000):
    """Paths (relative to top) of the regular files beneath top, no link followed."""
    found = []
    for root, dirs, files in os.walk(top):
        dirs[:] = sorted(d for d in dirs if not d.startswith('.'))
        for name in sorted(files):
            path = os.path.join(root, name)
            if _is_file(path):
                found.append(os.path.relpath(path, top))
                if len(found) >= limit:
                    return found
    return found


def _text(top, relative):
    try:
        return read_beneath(top, relative).decode(errors='replace')
    except OSError:
        return None


def _is_dir(path):
    try:
        return stat.S_ISDIR(os.lstat(path).st_mode)
    except OSError:
        return False


def _is_file(path):
    try:
        return stat.S_ISREG(os.lstat(path).st_mode)
    except OSError:
        return False


def layout(robot_dir, robot_name, chaser_dir):
    """(passed, evidence, judged) of course_layout. meshes/ is optional; the world folder may be
    world/ (the description's tree) or worlds/ (its lessons)."""
    if robot_dir is None or chaser_dir is None:
        missing = [name for name, folder in (('the robot package', robot_dir),
                                              (submission.CHASER, chaser_dir)) if folder is None]
        return False, 'missing: %s' % ', '.join(missing), True
    missing = []

    def need(folder, package, path, what=None):
        if not (_is_file if what == 'file' else _is_dir)(os.path.join(folder, path)):
            missing.append('%s/%s' % (package, path))

    need(robot_dir, robot_name, 'launch/world.launch', 'file')
    need(robot_dir, robot_name, 'urdf')
    worlds = [name for name in ('worlds', 'world') if _is_dir(os.path.join(robot_dir, name))]
    if not worlds:
        missing.append('%s/worlds (or world)' % robot_name)
    elif not any(name.endswith('.world') for name in _files(os.path.join(robot_dir, worlds[0]))):
        missing.append('a .world file in %s/%s' % (robot_name, worlds[0]))
    for folder, package in ((robot_dir, robot_name), (chaser_dir, submission.CHASER)):
        need(folder, package, 'CMakeLists.txt', 'file')
        need(folder, package, 'package.xml', 'file')
    need(chaser_dir, submission.CHASER, 'launch/ball_chaser.launch', 'file')
    if not any(_is_dir(os.path.join(chaser_dir, name)) for name in ('src', 'scripts')):
        missing.append('%s/src (or scripts)' % submission.CHASER)
    need(chaser_dir, submission.CHASER, 'srv/DriveToTarget.srv', 'file')
    named = '' if robot_name == 'my_robot' else ' (the robot package is named `%s`, not my_robot)' % robot_name
    if missing:
        return False, 'missing from the course\'s layout: %s%s' % (_shown(missing), named), True
    return True, ('%s has launch/, urdf/, %s/; %s has launch/, %s/, srv/DriveToTarget.srv%s'
                  % (robot_name, worlds[0], submission.CHASER,
                     'src' if _is_dir(os.path.join(chaser_dir, 'src')) else 'scripts', named)), True


def _cmake_commands(text, command):
    """The arguments of each call of command in a CMakeLists.txt, comments left out."""
    text = re.sub(r'#[^\n]*', '', text)
    return [args.split() for args in re.findall(r'\b%s\s*\(([^)]*)\)' % command, text, re.IGNORECASE)]


def cpp_nodes(chaser_dir):
    """(passed, evidence, judged): ball_chaser's CMakeLists.txt builds both nodes from C++."""
    if chaser_dir is None:
        return False, 'no %s package' % submission.CHASER, True
    text = _text(chaser_dir, 'CMakeLists.txt')
    if text is None:
        return False, NOT_JUDGED + '%s has no readable CMakeLists.txt' % submission.CHASER, False
    built, missing = [], []
    executables = _cmake_commands(text, 'add_executable')
    for node in NODES:
        sources = [(args[0], [arg for arg in args[1:] if CPP_SOURCE.search(arg)]) for args in executables
                   if args and (node in args[0] or any(node in os.path.basename(arg) for arg in args[1:]))]
        sources = [(target, files) for target, files in sources if files]
        if sources:
            built.append('%s from %s' % (sources[0][0], ', '.join(sources[0][1])))
        else:
            missing.append(node)
    if not missing:
        return True, 'CMakeLists.txt builds C++ nodes: %s' % '; '.join(built), True
    scripts = [path for path in _files(chaser_dir) if path.endswith('.py')
               and any(os.path.basename(path).startswith(node) for node in missing)]
    if scripts:
        return False, ('%s %s Python (%s); the course asks for C++ nodes'
                       % (' and '.join(missing), 'is' if len(missing) == 1 else 'are', _shown(scripts))), True
    return False, ('CMakeLists.txt has no add_executable of %s from a C++ source%s'
                   % (' or '.join(missing), '; it builds %s' % '; '.join(built) if built else '')), True


# What shows a colour test other than white: a hue (an HSV image), a colour parameter.
ANY_COLOUR = re.compile(r'COLOR_\w*2HSV|\bhsv\b|\bhue\b|(get)?[pP]aram\w*\s*\(\s*["\'][^"\']*colou?r',
                        re.IGNORECASE)
# A pixel's channel compared below a level: a colour other than white has a dark channel.
DARK_CHANNEL = re.compile(r'((\bdata|\bpixel\w*|\bimg\w*|\bimage\w*)\s*\[[^\]]*\]|\b(r|g|b|red|green|blue))'
                          r'\s*(<|<=)\s*\d+', re.IGNORECASE)
WHITE_TEST = re.compile(r'(==|>=|>)\s*(25[0-5]|2[0-4]\d)\b|\bwhite\w*\s*=', re.IGNORECASE)


def ball_colour(chaser_dir):
    """(passed, evidence, judged): process_image's source tests a colour other than white, tests
    only white, or (not judged) says neither plainly."""
    if chaser_dir is None:
        return False, NOT_JUDGED + 'no %s package' % submission.CHASER, False
    sources = [path for path in _files(chaser_dir)
               if os.path.basename(path).startswith('process_image')
               and (CPP_SOURCE.search(path) or path.endswith('.py'))]
    if not sources:
        return False, NOT_JUDGED + 'no process_image source in %s' % submission.CHASER, False
    white = None
    for path in sources:
        lines = (_text(chaser_dir, path) or '').splitlines()
        for number, line in enumerate(lines, 1):
            code = line.split('//')[0] if not path.endswith('.py') else line.split('#')[0]
            if ANY_COLOUR.search(code) or DARK_CHANNEL.search(code):
                return True, ('process_image tests a colour other than white: `%s` (%s:%d)'
                              % (code.strip()[:80], path, number)), True
            if white is None and WHITE_TEST.search(code):
                white = (code.strip()[:80], path, number)
    if white is not None:
        return False, ('process_image looks for white only: `%s` (%s:%d); no other colour is tested'
                       % white), True
    return False, (NOT_JUDGED + 'the colour test of %s could not be read plainly from its source'
                   % _shown(sources)), False


def _model_finder(top):
    """model_text(name): the model.sdf of a folder named name beneath top (a model folder the
    Building Editor saved), or None."""
    def model_text(name):
        for path in _files(top):
            parts = path.split(os.sep)
            if len(parts) >= 2 and parts[-2] == name and parts[-1].endswith('.sdf'):
                return _text(top, path)
        return None
    return model_text


def world_files(robot_dir):
    return [path for path in _files(robot_dir) if path.endswith('.world')]


def building_editor_in_files(robot_dir):
    """(passed, evidence, judged) over the robot package's worlds, when the launched one was not
    seen: passed when one of them was made with the Building Editor."""
    if robot_dir is None:
        return False, NOT_JUDGED + 'no robot package', False
    worlds = world_files(robot_dir)
    if not worlds:
        return False, 'the robot package holds no .world file', True
    finder, seen = _model_finder(robot_dir), None
    for path in worlds:
        verdict = building_editor(_text(robot_dir, path) or '', path, finder)
        if verdict[0]:
            return verdict[0], verdict[1] + ' (read from the files: the launched world was not seen)', True
        seen = seen or verdict
    return seen


def skid_steer_in_files(robot_dir):
    """(passed, evidence, judged) from the text of the robot package's robot descriptions, when no
    URDF was spawned (xacro is run only in the sandbox)."""
    if robot_dir is None:
        return False, NOT_JUDGED + 'no robot package', False
    for path in _files(robot_dir):
        if path.endswith(ROBOT_FILES) and SKID_STEER_PLUGIN in (_text(robot_dir, path) or ''):
            return True, '%s names the skid steer drive plugin (%s)' % (path, SKID_STEER_PLUGIN), True
    return False, ('no robot description of the robot package names %s (read from its files)'
                   % SKID_STEER_PLUGIN), True


def file_rows(found, not_spawned='the robot was not spawned'):
    """{row: (passed, evidence, judged)} judged from a submission.Submission's files; the rows that
    need the run are not judged for not_spawned until the run judges them."""
    robot_dir = found.robot.path if found.robot is not None else None
    chaser_dir = found.chaser.path if found.chaser is not None else None
    robot_name = found.robot.name if found.robot is not None else None
    rows = {
        'course_layout': layout(robot_dir, robot_name, chaser_dir),
        'robot_differs_from_sample': (False, NOT_JUDGED + '%s: its URDF comes from xacro, run only '
                                      'with the submission\'s nodes' % not_spawned, False),
        'robot_housed_in_world': (False, NOT_JUDGED + not_spawned, False),
        'building_editor_world': building_editor_in_files(robot_dir),
        'cpp_nodes': cpp_nodes(chaser_dir),
        'skid_steer': skid_steer_in_files(robot_dir),
        'ball_any_colour': ball_colour(chaser_dir),
    }
    return rows


def parse_rows(text):
    """--rubric's rows: a comma-separated list of names from ROW_NAMES ('all': every one)."""
    names = [name.strip() for name in str(text).split(',') if name.strip()]
    if names == ['all']:
        return tuple(ROW_NAMES)
    unknown = [name for name in names if name not in ROW_NAMES]
    if unknown:
        raise ValueError('unknown rubric row%s %s; the rows are %s (or all)'
                         % ('' if len(unknown) == 1 else 's', ', '.join(unknown), ', '.join(ROW_NAMES)))
    return tuple(name for name in ROW_NAMES if name in names)
