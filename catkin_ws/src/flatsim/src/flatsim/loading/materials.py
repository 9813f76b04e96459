"""Visual colours as Gazebo shows them: SDF <material> colours over Gazebo's material scripts.

Gazebo takes a visual's base colours from its material script (for example
Gazebo/Grey in media/materials/scripts/gazebo.material); explicit <ambient>,
<diffuse> and <emissive> in the SDF override the script's values one by one.
A textured script multiplies every colour by its texture, so a wall with
ambient 1 1 1 1 over Gazebo/Bricks still looks like bricks. Here each texture
is reduced to its average colour (TEXTURE_TINT values are estimates).

One display colour summarises the Blinn-Phong terms for a 2.5D renderer:
    colour = emissive + scene_ambient * ambient + (1 - scene_ambient) * diffuse
which gives Gazebo's look under its default 0.4 scene ambient and sun. A visual
is "unlit white" when Gazebo would draw it saturated white whatever the light:
white emissive, or white ambient and white diffuse. Only such a visual gets the
colour (1, 1, 1); any other colour that sums to white is pulled just below it,
so that a "pixel == 255" ball detector sees nothing else.
"""
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Optional, Tuple

from flatsim.errors import FlatsimError

RGBA = Tuple[float, float, float, float]

BLACK = (0.0, 0.0, 0.0, 1.0)
DEFAULT_SCENE_AMBIENT = (0.4, 0.4, 0.4)
DEFAULT_SCRIPT = 'Gazebo/Grey'
# The brightest a display colour gets unless the visual is unlit white.
BELOW_WHITE = 254.0 / 255.0


@dataclass(frozen=True)
class ScriptMaterial:
    ambient: RGBA
    diffuse: RGBA
    emissive: RGBA = BLACK
    texture_tint: Tuple[float, float, float] = (1.0, 1.0, 1.0)


def _grey(level, alpha=1.0):
    return (level, level, level, alpha)


def _rgb(r, g, b, a=1.0):
    return (r, g, b, a)


# Pass colours from Gazebo's gazebo.material; Ogre's default diffuse (white)
# where a script sets only ambient.
GAZEBO_MATERIALS = {
    'Gazebo/Grey': ScriptMaterial(_grey(0.3), _grey(0.7)),
    'Gazebo/Gray': ScriptMaterial(_grey(0.3), _grey(0.7)),
    'Gazebo/DarkGrey': ScriptMaterial(_grey(0.175), _grey(0.175)),
    'Gazebo/DarkGray': ScriptMaterial(_grey(0.175), _grey(0.175)),
    'Gazebo/White': ScriptMaterial(_grey(1.0), _grey(1.0)),
    'Gazebo/FlatBlack': ScriptMaterial(_grey(0.1), _grey(0.1)),
    'Gazebo/Black': ScriptMaterial(_grey(0.0), _grey(0.0)),
    'Gazebo/Red': ScriptMaterial(_rgb(1, 0, 0), _rgb(1, 0, 0)),
    'Gazebo/RedBright': ScriptMaterial(_rgb(0.87, 0.26, 0.07), _rgb(0.87, 0.26, 0.07)),
    'Gazebo/Green': ScriptMaterial(_rgb(0, 1, 0), _rgb(0, 1, 0)),
    'Gazebo/Blue': ScriptMaterial(_rgb(0, 0, 1), _rgb(0, 0, 1)),
    'Gazebo/SkyBlue': ScriptMaterial(_rgb(0.13, 0.44, 0.70), _rgb(0, 0, 1)),
    'Gazebo/Yellow': ScriptMaterial(_rgb(1, 1, 0), _rgb(1, 1, 0)),
    'Gazebo/ZincYellow': ScriptMaterial(_rgb(0.9725, 0.9529, 0.2078), _rgb(0.9725, 0.9529, 0.2078)),
    'Gazebo/DarkYellow': ScriptMaterial(_rgb(0.7, 0.7, 0), _rgb(0.7, 0.7, 0)),
    'Gazebo/Purple': ScriptMaterial(_rgb(1, 0, 1), _rgb(1, 0, 1)),
    'Gazebo/Turquoise': ScriptMaterial(_rgb(0, 1, 1), _rgb(0, 1, 1)),
    'Gazebo/Orange': ScriptMaterial(_rgb(1, 0.5088, 0.0468), _rgb(1, 0.5088, 0.0468)),
    'Gazebo/Indigo': ScriptMaterial(_rgb(0.33, 0, 0.5), _rgb(0.33, 0, 0.5)),
    'Gazebo/Gold': ScriptMaterial(_rgb(0.4, 0.24869, 0.020759), _rgb(0.8, 0.64869, 0.120759)),
    'Gazebo/Pioneer2Body': ScriptMaterial(_rgb(0.481193, 0.000123, 0.000123),
                                          _rgb(0.681193, 0.000923, 0.000923)),
    'Gazebo/WhiteGlow': ScriptMaterial(_grey(1.0), _grey(1.0), _grey(1.0)),
    'Gazebo/RedGlow': ScriptMaterial(_rgb(1, 0, 0), _rgb(1, 0, 0), _rgb(1, 0, 0)),
    'Gazebo/GreenGlow': ScriptMaterial(_rgb(0, 1, 0), _rgb(0, 1, 0), _rgb(0, 1, 0)),
    'Gazebo/BlueGlow': ScriptMaterial(_rgb(0, 0, 1), _rgb(0, 0, 1), _rgb(0, 0, 1)),
    'Gazebo/YellowGlow': ScriptMaterial(_rgb(1, 1, 0), _rgb(1, 1, 0), _rgb(1, 1, 0)),
    'Gazebo/PurpleGlow': ScriptMaterial(_rgb(1, 0, 1), _rgb(1, 0, 1), _rgb(1, 0, 1)),
    'Gazebo/TurquoiseGlow': ScriptMaterial(_rgb(0, 1, 1), _rgb(0, 1, 1), _rgb(0, 1, 1)),
    'Gazebo/LightOn': ScriptMaterial(_rgb(0, 1, 0), _rgb(0, 1, 0), _rgb(0, 1, 0)),
    'Gazebo/LightOff': ScriptMaterial(_rgb(1, 0, 0), _rgb(1, 0, 0), _rgb(1, 0, 0)),
    'Gazebo/RedTransparent': ScriptMaterial(_rgb(1, 0, 0, 0.5), _rgb(1, 0, 0, 0.5)),
    'Gazebo/GreenTransparent': ScriptMaterial(_rgb(0, 1, 0, 0.5), _rgb(0, 1, 0, 0.5)),
    'Gazebo/BlueTransparent': ScriptMaterial(_rgb(0, 0, 1, 0.5), _rgb(0, 0, 1, 0.5)),
    'Gazebo/YellowTransparent': ScriptMaterial(_rgb(1, 1, 0, 0.5), _rgb(1, 1, 0, 0.5)),
    'Gazebo/OrangeTransparent': ScriptMaterial(_rgb(1, 0.44, 0, 0.6), _rgb(1, 0.44, 0, 0.6)),
    'Gazebo/GreyTransparent': ScriptMaterial(_grey(0.5, 0.5), _grey(0.5, 0.5)),
    'Gazebo/DarkMagentaTransparent': ScriptMaterial(_rgb(0.6, 0, 0.6, 0.5), _rgb(0.6, 0, 0.6, 0.5)),
    # Textured scripts: pass colours times the texture's average colour.
    'Gazebo/Wood': ScriptMaterial(_grey(1.0), _grey(1.0), texture_tint=(0.62, 0.45, 0.28)),
    'Gazebo/Bricks': ScriptMaterial(_grey(1.0), _grey(1.0), texture_tint=(0.62, 0.33, 0.24)),
    'Gazebo/WoodFloor': ScriptMaterial(_grey(0.5), _grey(1.0), texture_tint=(0.55, 0.38, 0.22)),
    'Gazebo/WoodPallet': ScriptMaterial(_grey(0.5), _grey(1.0), texture_tint=(0.65, 0.52, 0.36)),
    'Gazebo/CeilingTiled': ScriptMaterial(_grey(0.5), _grey(1.0), texture_tint=(0.82, 0.82, 0.80)),
    'Gazebo/PaintedWall': ScriptMaterial(_grey(1.0), _grey(1.0), texture_tint=(0.87, 0.85, 0.80)),
    'Gazebo/WindowFrame': ScriptMaterial(_grey(1.0), _grey(1.0), texture_tint=(0.75, 0.75, 0.75)),
    'Gazebo/PioneerBody': ScriptMaterial(_rgb(0.5, 0, 0), _rgb(1, 0, 0), texture_tint=(0.9, 0.9, 0.9)),
    'Gazebo/Grass': ScriptMaterial(_grey(0.5), _grey(1.0), texture_tint=(0.30, 0.50, 0.20)),
    'Gazebo/Road': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.35, 0.35, 0.35)),
    'Gazebo/Motorway': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.35, 0.35, 0.35)),
    'Gazebo/Residential': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.5, 0.5, 0.5)),
    'Gazebo/Tertiary': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.5, 0.5, 0.5)),
    'Gazebo/Primary': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.4, 0.4, 0.4)),
    'Gazebo/Secondary': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.4, 0.4, 0.4)),
    'Gazebo/Trunk': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.4, 0.4, 0.4)),
    'Gazebo/Pedestrian': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.65, 0.63, 0.60)),
    'Gazebo/Footway': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.65, 0.63, 0.60)),
    'Gazebo/Steps': ScriptMaterial(_grey(0.1), _grey(0.8), texture_tint=(0.6, 0.6, 0.6)),
}


@dataclass(frozen=True)
class VisualColor:
    ambient: RGBA
    diffuse: RGBA
    emissive: RGBA
    color: RGBA                 # one display colour, see the module docstring
    unlit_white: bool
    script_known: bool          # False: a script name not in GAZEBO_MATERIALS


@lru_cache(maxsize=4096)
def parse_rgba(text):
    """SDF colour text ("r g b" or "r g b a", 0..1) as an RGBA tuple, or None when empty."""
    if text is None or not text.strip():
        return None
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        raise FlatsimError('colour %r is not numbers' % text) from None
    if len(values) == 3:
        values.append(1.0)
    if len(values) != 4 or not all(math.isfinite(v) for v in values):
        raise FlatsimError('colour %r is not 3 or 4 finite numbers' % text)
    return tuple(min(max(v, 0.0), 1.0) for v in values)


def _is_white(rgba):
    return all(channel >= 1.0 for channel in rgba[:3])


def _tinted(rgba, tint):
    return (rgba[0] * tint[0], rgba[1] * tint[1], rgba[2] * tint[2], rgba[3])


@lru_cache(maxsize=4096)
def resolve_visual_color(script_name: Optional[str] = None, ambient: Optional[RGBA] = None,
                         diffuse: Optional[RGBA] = None, emissive: Optional[RGBA] = None,
                         transparency: float = 0.0,
                         scene_ambient=DEFAULT_SCENE_AMBIENT) -> VisualColor:
    """Combine explicit SDF colours (which win) with a material script's colours.

    Arguments must be hashable (tuples): results are cached, as worlds repeat a few materials.
    """
    script = GAZEBO_MATERIALS.get(script_name) if script_name else None
    script_known = script is not None or not script_name
    base = script or GAZEBO_MATERIALS[DEFAULT_SCRIPT]
    tint = base.texture_tint
    ambient = _tinted(ambient or base.ambient, tint)
    diffuse = _tinted(diffuse or base.diffuse, tint)
    emissive = _tinted(emissive or base.emissive, tint)
    opacity = min(max(1.0 - float(transparency), 0.0), 1.0)
    alpha = diffuse[3] * opacity
    unlit_white = _is_white(emissive) or (_is_white(ambient) and _is_white(diffuse))
    if unlit_white:
        color = (1.0, 1.0, 1.0, alpha)
    else:
        rgb = [min(emissive[i] + scene_ambient[i] * ambient[i] + (1.0 - scene_ambient[i]) * diffuse[i], 1.0)
               for i in range(3)]
        if _is_white(rgb):
            rgb = [BELOW_WHITE] * 3
        color = (rgb[0], rgb[1], rgb[2], alpha)
    return VisualColor(ambient, diffuse, emissive, color, unlit_white, script_known)
