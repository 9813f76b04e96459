"""Pictures of a chase from above: the world as flatsim simulates it, the robot's path, its start
and end, and the ball. The report's trajectory.png and the grader's trial pictures are drawn here.

No ROS here.
"""
from dataclasses import dataclass
from typing import Dict

import cv2
import numpy as np

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world, white_balls
from flatsim.ros.overhead import fit_frame, moving_indices, render_static
from flatsim.world.scene import Scene
from flatsim.world.sim import Simulation

MAP_RESOLUTION = 0.01                          # m per pixel, unless the world is too big
MAP_MAX_PIXELS = 1000
PATH_COLOR = (230, 30, 30)
START_COLOR = (20, 170, 60)
END_COLOR = (40, 90, 230)
BALL_MARK_COLOR = (255, 0, 255)
TEXT_COLOR = (0, 0, 0)
MARK_RADIUS_PX = 6


@dataclass
class WorldMap:
    """The world as flatsim sees it: its scene, which primitives stay put, where balls start."""
    scene: Scene
    static: np.ndarray
    balls: Dict[str, tuple]                    # name -> (x, y, radius)
    path: str = ''


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
    return WorldMap(sim.scene, static, balls, str(path))


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
