"""Pictures of a chase from above: the world as flatsim simulates it, the robot's path, its start
and end, and the ball. The report's trajectory.png and the grader's trial pictures are drawn here.

A trial's picture (render_trial) is zoomed on the trial, with a scale bar, and shows what
flatsim simulates: the colliders that stop a robot at its working height (a table's legs, not
its top), the robot's outline and heading at the start and the end, its camera's view at the
start, and the ball.

No ROS here.
"""
import math
from dataclasses import dataclass, field
from typing import Dict, Optional, Sequence, Tuple

import cv2
import numpy as np

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world, white_balls
from flatsim.ros.overhead import (CONE_COLOR, MapFrame, draw_cones, draw_prims, fit_frame, moving_indices,
                                  render_static, rgb8, scene_bounds)
from flatsim.world.scene import Scene
from flatsim.world.model_geometry import is_obstacle
from flatsim.world.sim import Simulation

MAP_RESOLUTION = 0.01                          # m per pixel, unless the world is too big
MAP_MAX_PIXELS = 1000
PATH_COLOR = (230, 30, 30)
START_COLOR = (20, 170, 60)
END_COLOR = (40, 90, 230)
BALL_MARK_COLOR = (255, 0, 255)
TEXT_COLOR = (0, 0, 0)
MARK_RADIUS_PX = 6
# A trial's picture: at most this fine and this large, around the trial with this margin, and
# never narrower than the minimum span (a short trial still shows its surroundings).
TRIAL_RESOLUTION = 0.005
TRIAL_MAX_PIXELS = 800
TRIAL_MARGIN_M = 0.5
TRIAL_MIN_SPAN_M = 2.0
OBSTACLE_COLOR = (40, 40, 40)
# The camera's view at the start reaches this far past the ball.
WEDGE_PAST_BALL_M = 0.5
SCALE_BAR_STEPS_M = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0)


@dataclass
class WorldMap:
    """The world as flatsim sees it: its scene, which primitives stay put, where balls start."""
    scene: Scene
    static: np.ndarray
    balls: Dict[str, tuple]                    # name -> (x, y, radius)
    path: str = ''
    # The colliders that stop a robot (flatsim's is_obstacle), balls left out.
    obstacles: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))


def load_world_map(path, notes, model_paths=None):
    """The WorldMap of an SDF world, or an empty one (with a note) if it cannot be read.
    model_paths: where its includes are looked up (by default Gazebo's model path now)."""
    if not path:
        notes.append('no world file given: the map shows the path only')
        return WorldMap(Scene([]), np.zeros(0, dtype=int), {})
    try:
        world = load_world(path, model_paths)
        sim = Simulation(world)
    except (FlatsimError, OSError) as err:
        notes.append('the world could not be read, so the map shows the path only: %s' % err)
        return WorldMap(Scene([]), np.zeros(0, dtype=int), {}, str(path))
    moving = moving_indices(sim)
    static = np.setdiff1d(sim.scene.select(visual=True), moving)
    balls = {model.name: (model.pose.x, model.pose.y,
                          max(g.size[0] for g in model.visuals + model.collisions))
             for model in white_balls(world)}
    obstacles = np.array([index for index in np.setdiff1d(sim.scene.select(collision=True), moving)
                          if is_obstacle(sim.scene.prim(index))], dtype=int)
    return WorldMap(sim.scene, static, balls, str(path), obstacles)


def trajectory_frame(summary, world_map, ball):
    """The MapFrame of trajectory.png: the world plus everything the bag saw."""
    extents = [summary.robot.points()]
    if ball is not None:
        extents.append(ball.points())
    return fit_frame(world_map.scene, [e for e in extents if e.size], MAP_RESOLUTION,
                     max_pixels=MAP_MAX_PIXELS)


def _cv(frame, points):
    return np.round((frame.to_pixel(points) - 0.5) * 16).astype(np.int32)


def _circle(image, frame, point, radius_px, color, thickness):
    centre = _cv(frame, point)
    cv2.circle(image, (int(centre[0]), int(centre[1])), int(radius_px * 16), color, thickness,
               cv2.LINE_AA, 4)


def render_trajectory(summary, world_map, ball, ball_radius=0.1):
    """(image, frame): the world from above with the robot's path and the ball's places."""
    frame = trajectory_frame(summary, world_map, ball)
    image = render_static(world_map.scene, frame, world_map.static)
    robot = summary.robot.points()
    if len(robot):
        cv2.polylines(image, [_cv(frame, robot)], False, PATH_COLOR, 3, cv2.LINE_AA, 4)
        _circle(image, frame, robot[0], MARK_RADIUS_PX + 2, START_COLOR, 3)
        _circle(image, frame, robot[-1], MARK_RADIUS_PX, END_COLOR, -1)
    if ball is not None:
        radius_px = max(MARK_RADIUS_PX, ball_radius / frame.resolution)
        if len(ball) > 1:
            cv2.polylines(image, [_cv(frame, ball.points())], False, BALL_MARK_COLOR, 1,
                          cv2.LINE_AA, 4)
        _circle(image, frame, ball.points()[0], radius_px + 4, BALL_MARK_COLOR, 2)
        _circle(image, frame, ball.points()[-1], radius_px, BALL_MARK_COLOR, -1)
    legend = [('path', PATH_COLOR), ('start', START_COLOR), ('end', END_COLOR),
              ('ball', BALL_MARK_COLOR)]
    for row, (label, color) in enumerate(legend):
        y = 18 + 18 * row
        cv2.rectangle(image, (8, y - 10), (20, y + 2), color, -1)
        cv2.putText(image, label, (26, y), cv2.FONT_HERSHEY_SIMPLEX, 0.45, TEXT_COLOR, 1,
                    cv2.LINE_AA)
    return image, frame


def write_png(path, rgb):
    """Write an rgb8 picture as a PNG at path."""
    if not cv2.imwrite(path, cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)):
        raise FlatsimError('could not write %s' % path)


@dataclass
class TrialPicture:
    """What a trial's picture shows. robot: (N, 3) x, y, yaw over the trial; ball: (N, 2);
    footprint: the robot's outline in its own frame (counter-clockwise corners); camera: (x, y,
    yaw, hfov) of its camera at the start, or None; title: the trial's number and outcome."""
    robot: np.ndarray
    ball: np.ndarray
    ball_radius: float
    footprint: Sequence[Tuple[float, float]] = ()
    camera: Optional[Tuple[float, float, float, float]] = None
    title: str = ''

    def __post_init__(self):
        self.robot = np.asarray(self.robot, dtype=float).reshape(-1, 3)
        self.ball = np.asarray(self.ball, dtype=float).reshape(-1, 2)


def outline_at(footprint, x, y, yaw):
    """The footprint's corners in the world for a robot at (x, y, yaw)."""
    corners = np.asarray(footprint, dtype=float).reshape(-1, 2)
    cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
    return np.column_stack([x + cos_yaw * corners[:, 0] - sin_yaw * corners[:, 1],
                            y + sin_yaw * corners[:, 0] + cos_yaw * corners[:, 1]])


def trial_frame(picture):
    """The MapFrame of a trial's picture: its path, the ball and the camera, with a margin."""
    points = [picture.robot[:, :2], picture.ball]
    for x, y, yaw in (picture.robot[0], picture.robot[-1]):
        points.append(outline_at(picture.footprint, x, y, yaw))
    return _frame_around(np.vstack([p for p in points if len(p)]), TRIAL_MAX_PIXELS)


def _frame_around(points, max_pixels):
    """A MapFrame holding the points (N, 2), at least TRIAL_MIN_SPAN_M across, with a margin."""
    low, high = points.min(axis=0), points.max(axis=0)
    centre, half = (low + high) / 2.0, np.maximum((high - low) / 2.0, TRIAL_MIN_SPAN_M / 2.0)
    low, high = centre - half, centre + half
    return MapFrame.around(float(low[0]), float(low[1]), float(high[0]), float(high[1]),
                           TRIAL_RESOLUTION, TRIAL_MARGIN_M, max_pixels)


def scale_bar_length(frame):
    """The longest of SCALE_BAR_STEPS_M that spans at most a fifth of the picture's width."""
    width_m = frame.x_max - frame.x_min
    fitting = [step for step in SCALE_BAR_STEPS_M if step <= width_m / 5.0]
    return fitting[-1] if fitting else SCALE_BAR_STEPS_M[0]


def render_trial(world_map, picture):
    """(image, frame): one trial from above, zoomed on it (TrialPicture says what it shows)."""
    frame = trial_frame(picture)
    image = frame.blank(rgb8(world_map.scene.floor_color))
    start, end = picture.robot[0], picture.robot[-1]
    if picture.camera is not None:
        x, y, yaw, hfov = picture.camera
        reach = math.hypot(*(picture.ball[0] - (x, y))) + picture.ball_radius + WEDGE_PAST_BALL_M
        draw_cones(image, frame, [(x, y, yaw, hfov, reach)])
    # Over the view: the camera does not see through them.
    draw_prims(image, frame, world_map.scene, world_map.obstacles, OBSTACLE_COLOR)
    radius_px = max(MARK_RADIUS_PX / 2.0, picture.ball_radius / frame.resolution)
    if len(picture.ball) > 1:
        cv2.polylines(image, [_cv(frame, picture.ball)], False, BALL_MARK_COLOR, 1, cv2.LINE_AA, 4)
    _circle(image, frame, picture.ball[0], radius_px + 3, BALL_MARK_COLOR, 2)
    _circle(image, frame, picture.ball[-1], radius_px, BALL_MARK_COLOR, -1)
    cv2.polylines(image, [_cv(frame, picture.robot[:, :2])], False, PATH_COLOR, 2, cv2.LINE_AA, 4)
    for (x, y, yaw), color, filled in ((start, START_COLOR, False), (end, END_COLOR, True)):
        _robot_mark(image, frame, picture.footprint, x, y, yaw, color, filled)
    _scale_bar(image, frame)
    legend = [('path', PATH_COLOR), ('start', START_COLOR), ('end', END_COLOR),
              ('ball', BALL_MARK_COLOR), ('obstacle', OBSTACLE_COLOR)]
    if picture.camera is not None:
        legend.append(('camera at start', CONE_COLOR))
    _legend(image, legend, top=40 if picture.title else 8)
    if picture.title:
        _label(image, picture.title, (8, 24), scale=0.6)
    return image, frame


def render_world(world_map, robot_pose=None, footprint=(), title=''):
    """(image, frame): the whole world from above as flatsim simulates it, for a world where no
    trial could be placed: the colliders that stop a robot, its balls, and the robot at
    robot_pose (x, y, yaw), if given."""
    outlines = [np.array([[x - r, y - r], [x + r, y + r]]) for x, y, r in world_map.balls.values()]
    if robot_pose is not None:
        outlines.append(outline_at(footprint, *robot_pose) if len(footprint) else np.array([robot_pose[:2]]))
    bounds = scene_bounds(world_map.scene, world_map.obstacles)
    if bounds is not None:
        outlines.append(np.array([bounds[:2], bounds[2:]]))
    frame = _frame_around(np.vstack(outlines) if outlines else np.zeros((1, 2)), MAP_MAX_PIXELS)
    image = frame.blank(rgb8(world_map.scene.floor_color))
    draw_prims(image, frame, world_map.scene, world_map.obstacles, OBSTACLE_COLOR)
    for x, y, radius in world_map.balls.values():
        _circle(image, frame, (x, y), max(MARK_RADIUS_PX / 2.0, radius / frame.resolution), BALL_MARK_COLOR, -1)
    legend = [('ball', BALL_MARK_COLOR), ('obstacle', OBSTACLE_COLOR)]
    if robot_pose is not None:
        _robot_mark(image, frame, footprint, *robot_pose, END_COLOR, True)
        legend.insert(0, ('robot', END_COLOR))
    _scale_bar(image, frame)
    _legend(image, legend, top=40 if title else 8)
    if title:
        _label(image, title, (8, 24), scale=0.6)
    return image, frame


def _robot_mark(image, frame, footprint, x, y, yaw, color, filled):
    """The robot's outline at a pose (a circle if its outline is unknown), and its heading as an
    arrow from its origin past its front edge."""
    outline = outline_at(footprint, x, y, yaw)
    if len(outline) >= 3:
        if filled:
            cv2.fillPoly(image, [_cv(frame, outline)], color, cv2.LINE_AA, 4)
        cv2.polylines(image, [_cv(frame, outline)], True, color, 2, cv2.LINE_AA, 4)
        front = float(np.max((outline - (x, y)) @ (math.cos(yaw), math.sin(yaw))))
    else:
        _circle(image, frame, (x, y), MARK_RADIUS_PX, color, -1 if filled else 2)
        front = MARK_RADIUS_PX * frame.resolution
    length = max(front * 1.5, 12 * frame.resolution)
    tip = (x + length * math.cos(yaw), y + length * math.sin(yaw))
    cv2.arrowedLine(image, tuple(int(v) for v in _cv(frame, (x, y))), tuple(int(v) for v in _cv(frame, tip)),
                    TEXT_COLOR, 2, cv2.LINE_AA, 4, 0.3)


def _scale_bar(image, frame):
    length_m = scale_bar_length(frame)
    length_px = int(round(length_m / frame.resolution))
    height = image.shape[0]
    left, bottom = 10, height - 12
    cv2.rectangle(image, (left - 4, bottom - 22), (left + length_px + 4, bottom + 6), (255, 255, 255), -1)
    cv2.line(image, (left, bottom), (left + length_px, bottom), TEXT_COLOR, 3)
    for end in (left, left + length_px):
        cv2.line(image, (end, bottom - 6), (end, bottom + 4), TEXT_COLOR, 2)
    label = ('%g m' % length_m) if length_m >= 1.0 else ('%g cm' % (100 * length_m))
    cv2.putText(image, label, (left, bottom - 9), cv2.FONT_HERSHEY_SIMPLEX, 0.45, TEXT_COLOR, 1, cv2.LINE_AA)


def _label(image, text, origin, scale=0.45):
    """Text on a white box, legible over any floor."""
    (width, height), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    x, y = origin
    cv2.rectangle(image, (x - 3, y - height - 4), (x + width + 3, y + base + 2), (255, 255, 255), -1)
    cv2.putText(image, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, scale, TEXT_COLOR, 1, cv2.LINE_AA)


def _legend(image, entries, top):
    for row, (label, color) in enumerate(entries):
        y = top + 10 + 18 * row
        cv2.rectangle(image, (8, y - 10), (20, y + 2), color, -1)
        _label(image, label, (26, y))
