"""When a chase has reached the ball: the two rules the tools use, side by side. Pure: no ROS.

- The centre rule (evaluate, demo, report): the robot's origin, as its
  odometry gives it, comes within CENTRE_REACH_M of the ball's centre. It
  needs nothing but the odometry and the ball's position, and suits the
  course's own robot, whose size is known.
- The surface rule (grade): the robot's outline (its footprint polygon, as
  flatsim's physics simulates it) comes within SURFACE_REACH_M of the ball's
  surface, or the ball has been pushed BALL_PUSHED_M from where it was placed.
  Students' robots differ in size and in where their origin lies, so the
  grader measures from what touches the ball.

The two can disagree. A small robot whose front is 0.1 m ahead of its origin,
stopped with the ball's centre 0.4 m ahead, has reached the ball by the centre
rule but stands 0.2 m short of its surface; a long robot whose front is 0.35 m
ahead of its origin, stopped 0.1 m short of the surface, has reached it by the
surface rule but not by the centre rule. Pushing the ball counts only for the
surface rule.
"""
import math

import numpy as np

# Centre rule: the robot's origin this close to the ball's centre (m).
CENTRE_REACH_M = 0.4
# Surface rule: the robot's outline this close to the ball's surface (m) ...
SURFACE_REACH_M = 0.15
# ... or the ball moved this far from where it was placed: nothing but contact moves it.
BALL_PUSHED_M = 0.05


def centre_gap(robot_xy, ball_xy):
    """Distance from the robot's origin to the ball's centre (m)."""
    return math.hypot(robot_xy[0] - ball_xy[0], robot_xy[1] - ball_xy[1])


def centre_reached(robot_xy, ball_xy, reach=CENTRE_REACH_M):
    """The centre rule: the robot's origin within reach of the ball's centre."""
    return centre_gap(robot_xy, ball_xy) <= reach


def polygon_distance(polygon, points):
    """Distance from each point (M, 2) to a convex counter-clockwise polygon; negative inside."""
    corners = np.asarray(polygon, dtype=float)
    points = np.atleast_2d(np.asarray(points, dtype=float))
    edges = np.roll(corners, -1, axis=0) - corners
    rel = points[:, None, :] - corners[None, :, :]
    along = np.clip(np.sum(rel * edges, axis=2) / np.sum(edges * edges, axis=1), 0.0, 1.0)
    nearest = corners[None, :, :] + along[..., None] * edges[None, :, :]
    distance = np.min(np.linalg.norm(points[:, None, :] - nearest, axis=2), axis=1)
    inside = np.all(edges[None, :, 0] * rel[..., 1] - edges[None, :, 1] * rel[..., 0] >= 0.0, axis=1)
    return np.where(inside, -distance, distance)


def surface_gaps(robot, robot_poses, ball_xy, ball_radius):
    """Gap from the robot's outline to the ball's surface, per row; negative when they overlap.

    robot: anything with a footprint (counter-clockwise (x, y) corners in its root link frame),
    such as a placement.RobotGeometry; robot_poses: (N, 3) x, y, yaw; ball_xy: (N, 2) or one
    (x, y).
    """
    poses = np.atleast_2d(np.asarray(robot_poses, dtype=float))
    ball = np.broadcast_to(np.asarray(ball_xy, dtype=float), (len(poses), 2))
    dx, dy = ball[:, 0] - poses[:, 0], ball[:, 1] - poses[:, 1]
    cos_yaw, sin_yaw = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    local = np.column_stack([cos_yaw * dx + sin_yaw * dy, cos_yaw * dy - sin_yaw * dx])
    return polygon_distance(robot.footprint, local) - ball_radius


def surface_reached_how(gap, ball_moved, reach=SURFACE_REACH_M):
    """The surface rule: '' when not reached, else how: the outline came within reach of the
    ball's surface (gap, as surface_gaps gives it), or the ball was pushed (ball_moved, m)."""
    if gap <= reach:
        return 'came within %.0f cm of the ball\'s surface' % (100 * reach)
    if ball_moved >= BALL_PUSHED_M:
        return 'pushed the ball'
    return ''
