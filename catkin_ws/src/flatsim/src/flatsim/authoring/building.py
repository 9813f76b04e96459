"""The Building Editor's output: walls with doors and windows as one static model.

A design is walls drawn as segments (x1, y1)-(x2, y2) on the floor, each with
a thickness, a height and a colour, and openings (doors and windows) each on
a wall at an offset along it. The model is what Gazebo's Building Editor
writes (~/building_editor_models/NAME/model.sdf): a static model whose pose is
the centre of the walls' bounding box, one link per wall named Wall_0,
Wall_1, ... at the wall's centre and heading, and a box visual and collision
named Wall_N_Visual and Wall_N_Collision; a wall with openings is cut into the
boxes around its holes, Wall_N_Visual_0, Wall_N_Collision_0, ... Each wall box
reaches half a thickness past both ends of its segment, so walls that meet
at a corner close it. Doors and windows leave holes; like Gazebo's, they
are not models of their own.

The editor snaps a point the user draws to the end of another wall near it,
else to the grid (snap_point); the browser does the same live, and the
server applies this rule to a design it receives. The browser learns the
grid, the snap radius, the defaults and the limits from editor_settings(),
which the studio sends it when it connects, so that they are held here only.
No ROS here.
"""
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

from flatsim.authoring.model_writer import MAX_SIZE, ModelDesign, check_name, model_config
from flatsim.authoring.sdf_text import child, is_finite, numbers, pose_text, to_text
from flatsim.errors import AuthoringError
from flatsim.pose import Pose

SDF_VERSION = '1.7'
RGBA = Tuple[float, float, float, float]
# Gazebo's Building Editor defaults, in metres.
WALL_THICKNESS = 0.15
WALL_HEIGHT = 2.5
WINDOW_WIDTH, WINDOW_HEIGHT, WINDOW_ELEVATION = 0.8, 0.8, 0.5
DOOR_WIDTH, DOOR_HEIGHT = 0.9, 2.0
WALL_COLOR = (1.0, 1.0, 1.0, 1.0)
# The materials the editor's texture buttons give (none, wood, tiles, bricks).
WALL_MATERIALS = ('Gazebo/Grey', 'Gazebo/Wood', 'Gazebo/CeilingTiled', 'Gazebo/Bricks')
GRID_STEP = 0.25            # m between grid points
END_SNAP_RADIUS = 0.25      # m within which a point goes to another wall's end
# Pieces of wall narrower than this (1 mm) between holes are not worth a box.
MIN_PIECE = 1e-3


@dataclass
class Wall:
    start: Tuple[float, float]
    end: Tuple[float, float]
    thickness: float = WALL_THICKNESS
    height: float = WALL_HEIGHT
    color: RGBA = WALL_COLOR
    material: str = 'Gazebo/Grey'


@dataclass
class Opening:
    wall: int                                  # index of the wall in BuildingDesign.walls
    offset: float                              # m from the wall's start to the opening's centre
    kind: str = 'door'                         # 'door' | 'window'
    width: float = DOOR_WIDTH
    height: float = DOOR_HEIGHT
    elevation: float = 0.0                     # m from the floor to the bottom (a window's sill)


def window(wall, offset, width=WINDOW_WIDTH, height=WINDOW_HEIGHT, elevation=WINDOW_ELEVATION):
    return Opening(wall, offset, 'window', width, height, elevation)


def door(wall, offset, width=DOOR_WIDTH, height=DOOR_HEIGHT):
    return Opening(wall, offset, 'door', width, height, 0.0)


@dataclass
class BuildingDesign:
    name: str
    walls: List[Wall]
    openings: List[Opening] = field(default_factory=list)


def wall_length(wall):
    return math.hypot(wall.end[0] - wall.start[0], wall.end[1] - wall.start[1])


def _check_point(point, what):
    if not (isinstance(point, (tuple, list)) and len(point) == 2 and is_finite(*point)):
        raise AuthoringError('%s must be two finite numbers, got %r' % (what, point))


def _check_positive(value, what):
    if not (is_finite(value) and value > 0):
        raise AuthoringError('%s must be a positive number, got %r' % (what, value))
    if value > MAX_SIZE:
        raise AuthoringError('%s is %g m, more than the %g m a building part may be'
                             % (what, value, MAX_SIZE))


def check_building(design):
    """AuthoringError naming the first thing wrong with the design; the design when all is well."""
    check_name(design.name, 'building')
    if not design.walls:
        raise AuthoringError('building %s has no wall' % design.name)
    for index, wall in enumerate(design.walls):
        what = 'Wall_%d' % index
        _check_point(wall.start, what + ' start')
        _check_point(wall.end, what + ' end')
        if wall_length(wall) < MIN_PIECE:
            raise AuthoringError('%s has no length: it starts and ends at %r' % (what, tuple(wall.start)))
        _check_positive(wall.thickness, what + ' thickness')
        _check_positive(wall.height, what + ' height')
        if not (isinstance(wall.color, (tuple, list)) and len(wall.color) == 4 and is_finite(*wall.color)
                and all(0.0 <= c <= 1.0 for c in wall.color)):
            raise AuthoringError('%s colour must be four numbers from 0 to 1, got %r' % (what, wall.color))
        if wall.material not in WALL_MATERIALS:
            raise AuthoringError('%s material must be one of %s, got %r'
                                 % (what, ', '.join(WALL_MATERIALS), wall.material))
    spans = {}
    for opening in design.openings:
        if opening.kind not in ('door', 'window'):
            raise AuthoringError('an opening is a door or a window, not %r' % (opening.kind,))
        if not (isinstance(opening.wall, int) and 0 <= opening.wall < len(design.walls)):
            raise AuthoringError('%s on wall %r: there is no such wall' % (opening.kind, opening.wall))
        wall = design.walls[opening.wall]
        what = '%s on Wall_%d' % (opening.kind, opening.wall)
        if not is_finite(opening.offset, opening.elevation):
            raise AuthoringError('%s: offset and elevation must be finite numbers' % what)
        _check_positive(opening.width, what + ' width')
        _check_positive(opening.height, what + ' height')
        if opening.elevation < 0:
            raise AuthoringError('%s: elevation %g is below the floor' % (what, opening.elevation))
        low, high = opening.offset - opening.width / 2, opening.offset + opening.width / 2
        length = wall_length(wall)
        if low < -1e-9 or high > length + 1e-9:
            raise AuthoringError('%s does not fit: it spans %g to %g m along a wall %g m long'
                                 % (what, low, high, length))
        if opening.elevation + opening.height > wall.height + 1e-9:
            raise AuthoringError('%s does not fit: its top at %g m is above the wall\'s %g m'
                                 % (what, opening.elevation + opening.height, wall.height))
        for other_low, other_high in spans.get(opening.wall, []):
            if low < other_high - 1e-9 and other_low < high - 1e-9:
                raise AuthoringError('%s overlaps another opening on that wall' % what)
        spans.setdefault(opening.wall, []).append((low, high))
    return design


def wall_pieces(wall, openings):
    """The boxes a wall is cut into: (centre x along the wall from its middle, centre z, length, height).

    Without openings, one box. With them: full-height pieces between the
    holes and at the ends, and a piece under (a window's sill) and over each hole.
    """
    length = wall_length(wall)
    start, end = -length / 2 - wall.thickness / 2, length / 2 + wall.thickness / 2
    holes = sorted((opening.offset - length / 2 - opening.width / 2,
                    opening.offset - length / 2 + opening.width / 2, opening) for opening in openings)
    pieces = []

    def piece(x0, x1, z0, z1):
        if x1 - x0 >= MIN_PIECE and z1 - z0 >= MIN_PIECE:
            pieces.append(((x0 + x1) / 2, (z0 + z1) / 2, x1 - x0, z1 - z0))

    cursor = start
    for low, high, opening in holes:
        piece(cursor, low, 0.0, wall.height)
        piece(low, high, 0.0, opening.elevation)
        piece(low, high, opening.elevation + opening.height, wall.height)
        cursor = high
    piece(cursor, end, 0.0, wall.height)
    return pieces


def _bounds_centre(walls):
    xs = [point[0] for wall in walls for point in (wall.start, wall.end)]
    ys = [point[1] for wall in walls for point in (wall.start, wall.end)]
    return (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2


def _box(link, tag, name, centre, size, wall):
    elem = child(link, tag, name=name)
    child(elem, 'pose', pose_text(centre))
    child(child(child(elem, 'geometry'), 'box'), 'size', numbers(size))
    if tag == 'visual':
        material = child(elem, 'material')
        script = child(material, 'script')
        child(script, 'uri', 'file://media/materials/scripts/gazebo.material')
        child(script, 'name', wall.material)
        child(material, 'ambient', numbers(wall.color))
        child(child(elem, 'meta'), 'layer', '0')
    else:
        child(elem, 'max_contacts', '10')


def building_sdf(design, origin: Optional[Tuple[float, float]] = None):
    """The model.sdf text of a building design (checked first).

    The model's pose is the centre of the walls' bounding box, as the editor
    places it; origin overrides it.
    """
    check_building(design)
    cx, cy = origin if origin is not None else _bounds_centre(design.walls)
    root = ET.Element('sdf', version=SDF_VERSION)
    model = child(root, 'model', name=design.name)
    child(model, 'pose', pose_text(Pose(cx, cy)))
    for index, wall in enumerate(design.walls):
        name = 'Wall_%d' % index
        (x1, y1), (x2, y2) = wall.start, wall.end
        link = child(model, 'link', name=name)
        child(link, 'pose', pose_text(Pose((x1 + x2) / 2 - cx, (y1 + y2) / 2 - cy,
                                           yaw=math.atan2(y2 - y1, x2 - x1))))
        openings = [opening for opening in design.openings if opening.wall == index]
        pieces = wall_pieces(wall, openings)
        for number, (x, z, length, height) in enumerate(pieces):
            suffix = '_%d' % number if openings else ''
            size = (length, wall.thickness, height)
            _box(link, 'visual', '%s_Visual%s' % (name, suffix), Pose(x, 0, z), size, wall)
            _box(link, 'collision', '%s_Collision%s' % (name, suffix), Pose(x, 0, z), size, wall)
    child(model, 'static', '1')
    return to_text(root)


def building_config(design, description='', author_name='', author_email=''):
    """model.config for the building, as the editor's save dialog writes it."""
    return model_config(ModelDesign(design.name, [], description=description, author_name=author_name,
                                    author_email=author_email))


def editor_settings(max_parts):
    """What the Building Editor in the browser draws with: the grid, the snap radius, the
    defaults of a new wall, door and window, and the limits of a design (max_parts: the
    most walls, and the most openings, the studio reads)."""
    return {'grid_step': GRID_STEP, 'snap_radius': END_SNAP_RADIUS, 'min_length': MIN_PIECE,
            'max_size': MAX_SIZE, 'max_parts': max_parts,
            'wall': {'thickness': WALL_THICKNESS, 'height': WALL_HEIGHT, 'color': list(WALL_COLOR)},
            'door': {'width': DOOR_WIDTH, 'height': DOOR_HEIGHT, 'elevation': 0.0},
            'window': {'width': WINDOW_WIDTH, 'height': WINDOW_HEIGHT, 'elevation': WINDOW_ELEVATION}}


def snap_to_grid(point, step=None):
    """The grid point nearest to point."""
    step = GRID_STEP if step is None else step
    _check_point(point, 'the point')
    _check_positive(step, 'the grid step')
    return tuple(round(value / step) * step for value in point)


def snap_point(point, walls, step=None, radius=None, skip=None):
    """Where a drawn point lands: the nearest end of another wall within radius, else the grid point.

    skip is the index of the wall being drawn, whose own ends do not attract.
    """
    _check_point(point, 'the point')
    best, best_distance = None, END_SNAP_RADIUS if radius is None else radius
    for index, wall in enumerate(walls):
        if index == skip:
            continue
        for end in (wall.start, wall.end):
            distance = math.hypot(end[0] - point[0], end[1] - point[1])
            if distance <= best_distance:
                best, best_distance = (float(end[0]), float(end[1])), distance
    return best if best is not None else snap_to_grid(point, step)


def snap_design(design, step=None, radius=None):
    """The design with every wall end snapped as the editor snaps it, wall by wall in order."""
    snapped = []
    for wall in design.walls:
        start = snap_point(wall.start, snapped, step, radius)
        end = snap_point(wall.end, snapped, step, radius)
        snapped.append(Wall(start, end, wall.thickness, wall.height, wall.color, wall.material))
    return BuildingDesign(design.name, snapped, list(design.openings))
