"""Would the robot stand? Its centre of mass against the support polygon of its ground contacts.

flatsim keeps every robot upright, so a design that would tip over in Gazebo
drives here as if it stood. This judges it from the URDF alone, with every
joint at zero:

- the centre of mass is the mass-weighted mean of the links' <inertial>
  origins, composed down the joints from the root link;
- the ground contacts are the lowest points of the collision shapes of the
  wheels (links turned by a continuous joint or by the drive plugin's joints)
  and of the casters (sphere collisions, and links named like a caster), those
  within CONTACT_TOLERANCE of the lowest of them all;
- the support polygon is the convex hull of the contacts on the ground plane.

The margin is the distance from the centre of mass to the polygon's nearest
edge: positive inside, negative outside. Two wheels and nothing else make a
line, not a polygon, so their margin is never positive.
"""
import math
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from flatsim.loading.urdf_robot import link_poses

# m: a design whose centre of mass is nearer the edge than this tips at the first bump or brake.
MIN_MARGIN = 0.02
# m: a wheel or caster this close above the lowest contact still touches the ground once the
# robot settles; the course's casters (radius 0.0499 under wheels of 0.1) sit 0.1 mm up.
CONTACT_TOLERANCE = 0.005
# m: points of one shape this close to its lowest point are all on the ground together
# (wheels turned by 1.5707 rather than pi/2 lean their ends a few micrometres apart).
FLAT_TOLERANCE = 1e-3
CIRCLE_POINTS = 32
CASTER_WORDS = ('caster', 'castor')


@dataclass(frozen=True)
class Stability:
    centre_of_mass: Tuple[float, float]            # m, in the root link frame, on the ground plane
    mass: float                                    # kg
    support: Tuple[Tuple[float, float], ...]       # counter-clockwise polygon (2 points: a line)
    contacts: Tuple[str, ...]                      # the links that touch the ground
    margin: float                                  # m; negative outside the polygon

    @property
    def stable(self):
        return self.margin >= MIN_MARGIN

    def describe(self):
        """One line with the numbers, saying whether the robot would tip."""
        where = ('%s m inside' % _metres(self.margin) if self.margin > 0
                 else 'on the edge of' if self.margin == 0 else '%s m outside' % _metres(-self.margin))
        polygon = ' '.join('(%s, %s)' % (_metres(x), _metres(y)) for x, y in self.support)
        shape = 'support polygon' if len(self.support) >= 3 else 'support line (no polygon)'
        text = ('centre of mass (%s, %s) m of %.2f kg is %s the %s %s of %s'
                % (_metres(self.centre_of_mass[0]), _metres(self.centre_of_mass[1]), self.mass, where,
                   shape, polygon, ', '.join(self.contacts)))
        if self.stable:
            return 'stable: %s' % text
        return ('may tip over: %s (margin %s m; a stable design keeps it at least %.2f m inside)'
                % (text, _metres(self.margin), MIN_MARGIN))


def _metres(value):
    # Adding 0.0 turns a -0.0 left by rounding into 0.0, so the polygon reads as it is.
    return '%.3f' % (round(value, 3) + 0.0)


def assess(spec) -> Tuple[Optional[Stability], str]:
    """(Stability, '') for a RobotSpec, or (None, why it cannot be judged)."""
    if spec.root_link == 'world':
        return None, 'fixed to the world'
    poses = link_poses(spec)
    masses, centres = [], []
    for name, link in spec.links.items():
        if link.mass > 0.0:
            masses.append(link.mass)
            centre = (poses[name] * link.centre_of_mass).matrix()[:3, 3]
            centres.append(centre)
    if not masses:
        return None, 'no link has a positive <inertial><mass>'
    centre = centre_of_mass(masses, centres)
    wheels_and_casters = contact_links(spec)
    candidates = []
    for name, link in spec.links.items():
        for kind, origin, size in link.collisions:
            if name in wheels_and_casters or kind == 'sphere':
                candidates.append((name, lowest_points(kind, poses[name].matrix() @ origin.matrix(), size)))
    if not candidates:
        return None, 'no wheels or casters: no collision shape of a wheel link, and no caster sphere'
    ground = min(float(points[:, 2].min()) for _name, points in candidates)
    touching = [(name, points[points[:, 2] <= ground + CONTACT_TOLERANCE]) for name, points in candidates]
    touching = [(name, points) for name, points in touching if len(points)]
    contact_xy = np.vstack([points[:, :2] for _name, points in touching])
    polygon = convex_hull(contact_xy)
    names = tuple(dict.fromkeys(name for name, _points in touching))
    return Stability(centre_of_mass=(float(centre[0]), float(centre[1])), mass=float(sum(masses)),
                     support=tuple((float(x), float(y)) for x, y in polygon), contacts=names,
                     margin=signed_margin(polygon, centre[:2])), ''


def contact_links(spec):
    """Links that are wheels or casters as a whole: turned by a continuous or drive joint,
    or named like a caster."""
    drive_joints = set()
    if spec.drive is not None:
        drive_joints = set(spec.drive.left_joints) | set(spec.drive.right_joints)
    wheels = {joint.child for joint in spec.joints.values()
              if joint.kind == 'continuous' or joint.name in drive_joints}
    casters = {name for name in spec.links if any(word in name.lower() for word in CASTER_WORDS)}
    return wheels | casters


def centre_of_mass(masses, centres):
    """Mass-weighted mean of (N, 3) centres."""
    masses = np.asarray(masses, dtype=float)
    return masses @ np.asarray(centres, dtype=float) / masses.sum()


def lowest_points(kind, matrix, size):
    """(M, 3) points where a collision shape, posed by a 4x4 matrix, touches a plane below it.

    A sphere touches at one point, a lying cylinder along a line (one point per end
    face), a standing cylinder or a flat box with a face."""
    centre, rotation = matrix[:3, 3], matrix[:3, :3]
    if kind == 'sphere':
        return np.array([centre - [0.0, 0.0, size[0]]])
    if kind == 'cylinder':
        radius, length = size
        axis = rotation[:, 2]
        down = np.array([0.0, 0.0, -1.0]) - np.dot([0.0, 0.0, -1.0], axis) * axis
        ends = [centre + axis * length / 2.0, centre - axis * length / 2.0]
        if np.linalg.norm(down) > 1e-9:
            down = down / np.linalg.norm(down)
            points = np.array([end + radius * down for end in ends])
        else:
            angles = np.linspace(0.0, 2.0 * math.pi, CIRCLE_POINTS, endpoint=False)
            ring = radius * (np.outer(np.cos(angles), rotation[:, 0]) + np.outer(np.sin(angles), rotation[:, 1]))
            points = np.vstack([end + ring for end in ends])
    elif kind == 'box':
        corners = np.array(np.meshgrid([-0.5, 0.5], [-0.5, 0.5], [-0.5, 0.5])).reshape(3, -1).T
        points = centre + (corners * np.asarray(size)) @ rotation.T
    else:
        return np.zeros((0, 3))
    return points[points[:, 2] <= points[:, 2].min() + FLAT_TOLERANCE]


def convex_hull(points):
    """Counter-clockwise convex hull of (N, 2) points (Andrew's monotone chain), without
    collinear vertices; two points for points on a line, one for a single point."""
    unique = sorted(set((float(x), float(y)) for x, y in np.asarray(points, dtype=float)))
    if len(unique) <= 2:
        return np.array(unique)

    def cross(origin, a, b):
        return (a[0] - origin[0]) * (b[1] - origin[1]) - (a[1] - origin[1]) * (b[0] - origin[0])

    def chain(ordered):
        hull = []
        for point in ordered:
            while len(hull) >= 2 and cross(hull[-2], hull[-1], point) <= 1e-12:
                hull.pop()
            hull.append(point)
        return hull[:-1]
    return np.array(chain(unique) + chain(unique[::-1]))


def signed_margin(polygon, point):
    """Distance from point to the nearest edge of a counter-clockwise convex polygon:
    positive inside, negative outside. A line or a point has no inside: minus the distance."""
    polygon = np.asarray(polygon, dtype=float)
    point = np.asarray(point, dtype=float)
    if len(polygon) == 1:
        return -float(np.linalg.norm(point - polygon[0]))
    edges = [(polygon[i], polygon[(i + 1) % len(polygon)]) for i in range(len(polygon))]
    if len(polygon) == 2:
        edges = edges[:1]
    distances = []
    for start, end in edges:
        edge = end - start
        along = min(1.0, max(0.0, float(np.dot(point - start, edge) / np.dot(edge, edge))))
        distances.append(float(np.linalg.norm(point - (start + along * edge))))
    nearest = min(distances)
    if len(polygon) == 2:
        return -nearest
    inside = all((end[0] - start[0]) * (point[1] - start[1]) - (end[1] - start[1]) * (point[0] - start[0]) >= 0.0
                 for start, end in edges)
    return nearest if inside else -nearest
