"""Stand-in shapes for the Gazebo model-database meshes that the course's worlds use.

flatsim draws boxes, cylinders and spheres and reads no mesh files, and
Gazebo's model database (model://...) is not installed here. A world that
shows something only through such a mesh would show nothing at all. For the
meshes listed here, the loader draws a stand-in made of boxes instead: the
mesh's real size (from its COLLADA file), times the <scale> of the <mesh>,
and its look reduced to plain colours. The loader says in its report that a
stand-in was drawn. Any other mesh is left out, with a report that says so.

The catalogue:

  model://number1/meshes/number.dae ... model://number4/meshes/number.dae
      Gazebo's number blocks (models number1..number4), used by the course's
      simple_arm world. Each mesh is a cube of side 0.8 m centred on its
      origin (a unit cube scaled by 0.4 in the COLLADA scene), textured white
      with a black digit on every face. The stand-in is a white box of that
      size with the digit drawn as thin black boxes, 3 x 5 pixel-font strokes,
      on the four side faces (upright) and the top (its head towards +y). The
      digit is the one the material script names (Number/One .. Number/Four,
      as the course's world picks one mesh and three scripts), else the
      model's own.

The colours follow the mesh's COLLADA effect: emission 0.2, ambient 0.9 and a
white diffuse texture make the white parts the brightest colour short of an
unlit white (so a "pixel == 255" ball detector still sees only the ball);
the texture's black modulates all of it to black.
"""
from dataclasses import dataclass
from typing import Optional, Tuple

from flatsim.loading.materials import resolve_visual_color

RGBA = Tuple[float, float, float, float]
Vec3 = Tuple[float, float, float]

NUMBER_BLOCK_SIDE = 0.8
NUMBER_WORDS = {'One': 1, 'Two': 2, 'Three': 3, 'Four': 4}
NUMBER_MESHES = {'model://number%d/meshes/number.dae' % digit: digit for digit in NUMBER_WORDS.values()}

# Digits as 3 x 5 pixels, top row first.
PIXEL_FONT = {
    1: ('.X.', 'XX.', '.X.', '.X.', 'XXX'),
    2: ('XXX', '..X', 'XXX', 'X..', 'XXX'),
    3: ('XXX', '..X', 'XXX', '..X', 'XXX'),
    4: ('X.X', 'X.X', 'XXX', '..X', '..X'),
}
# The digit's height and stroke relief, as fractions of the face it is drawn on.
DIGIT_HEIGHT = 0.6
RELIEF = 0.01

WHITE = resolve_visual_color(ambient=(0.9, 0.9, 0.9, 1.0), diffuse=(1.0, 1.0, 1.0, 1.0),
                             emissive=(0.2, 0.2, 0.2, 1.0)).color
BLACK = (0.0, 0.0, 0.0, 1.0)


@dataclass(frozen=True)
class Part:
    """One box of a stand-in, in the mesh's frame, scale applied."""
    name: str
    centre: Vec3
    size: Vec3
    color: RGBA
    visual_only: bool = False     # markings: drawn, but not part of the mesh's collision shape


@dataclass(frozen=True)
class StandIn:
    description: str
    parts: Tuple[Part, ...]


def has_stand_in(uri):
    return (uri or '').strip() in NUMBER_MESHES


def stand_in(uri, scale=(1.0, 1.0, 1.0), material=None) -> Optional[StandIn]:
    """The stand-in for a mesh uri at this <scale>, or None when the catalogue has none."""
    digit = NUMBER_MESHES.get((uri or '').strip())
    if digit is None:
        return None
    if material and material.startswith('Number/'):
        digit = NUMBER_WORDS.get(material[len('Number/'):], digit)
    size = tuple(NUMBER_BLOCK_SIDE * abs(s) for s in scale)
    parts = (Part('block', (0.0, 0.0, 0.0), size, WHITE),) + _digit_parts(digit, size)
    shape = ('%.2f m cube' % size[0] if size[0] == size[1] == size[2]
             else '%.2f x %.2f x %.2f m box' % size)
    return StandIn('a white %s with the digit %d on its faces' % (shape, digit), parts)


def _digit_parts(digit, size):
    """Black strokes of the digit on the four side faces and the top of a box of this size."""
    half = [s / 2.0 for s in size]
    parts = []
    # Each face: (name, normal axis and sign, right axis and sign, up axis), right and up as
    # seen from outside the face; the top face is read with its head towards +y.
    faces = (('x+', 0, 1, 1, 1, 2), ('x-', 0, -1, 1, -1, 2), ('y+', 1, 1, 0, -1, 2),
             ('y-', 1, -1, 0, 1, 2), ('z+', 2, 1, 0, 1, 1))
    for face, normal, normal_sign, right, right_sign, up in faces:
        pixel = DIGIT_HEIGHT * min(size[right], size[up]) / 5.0
        relief = RELIEF * size[normal]
        for index, (col, row, cols, rows) in enumerate(_strokes(PIXEL_FONT[digit])):
            centre = [0.0, 0.0, 0.0]
            extent = [0.0, 0.0, 0.0]
            centre[normal] = normal_sign * (half[normal] + relief / 2.0)
            extent[normal] = relief
            centre[right] = right_sign * (col + cols / 2.0 - 1.5) * pixel
            extent[right] = cols * pixel
            centre[up] = (2.5 - row - rows / 2.0) * pixel
            extent[up] = rows * pixel
            parts.append(Part('digit_%s_%d' % (face, index), tuple(centre), tuple(extent), BLACK,
                              visual_only=True))
    return tuple(parts)


def _strokes(rows):
    """Rectangles (col, row, cols, rows) covering a pixel font glyph: row runs merged downwards."""
    runs = []
    for row, line in enumerate(rows):
        col = 0
        while col < len(line):
            if line[col] != 'X':
                col += 1
                continue
            end = col
            while end < len(line) and line[end] == 'X':
                end += 1
            runs.append([col, row, end - col, 1])
            col = end
    merged = []
    for run in runs:
        above = next((m for m in merged if m[0] == run[0] and m[2] == run[2]
                      and m[1] + m[3] == run[1]), None)
        if above is not None:
            above[3] += 1
        else:
            merged.append(run)
    return [tuple(m) for m in merged]
