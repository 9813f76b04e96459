"""A report of a chase from a ROS 1 bag: a map with the path, the ball's first sight, a summary.

  rosrun chase_tools report BAG [--world WORLD] [--output DIR] [--robot my_robot] [--ball NAME]

No ROS here: the bag is read with rosbags, so no master is needed. A bag that
lacks topics, was never closed, or was cut short still gives a report of what
it holds, with a note of what is missing in summary.md and on stderr.

Writes into the output folder:
  trajectory.png  the world from above (the same 2.5D primitives flatsim uses),
                  the robot's path, its start and end, the ball where it was
  first_sight.png the first recorded camera frame with a pure white pixel (summary.md
                  says how close to the camera's own first sight it is)
  summary.md      outcome, time to reach, path length, camera frames, real-time factor
"""
import argparse
import os
import sys
from dataclasses import dataclass
from typing import List, Optional

import numpy as np

from chase_tools import arguments
from chase_tools.bag_tracks import ROBOT_NAME, Track, read_bag
from chase_tools.drawing import load_world_map, render_trajectory, write_png
from chase_tools.reach import CENTRE_REACH_M
from flatsim.errors import FlatsimError

REACH_M = CENTRE_REACH_M
_NO_ROBOT = 'no robot pose in the bag'


# -- the outcome and the report --------------------------------------------------------------
@dataclass
class Outcome:
    reached: bool
    time_to_reach: Optional[float]             # s of sim time from the start of the bag
    closest: Optional[float]                   # m, robot origin to ball centre
    start_time: float = 0.0


def ball_track(summary, world_map, ball_name):
    """The ball's track from the bag, else its place in the world file, else None."""
    if len(summary.ball):
        return summary.ball
    if ball_name in world_map.balls:
        x, y, _ = world_map.balls[ball_name]
        start = summary.robot.t[0] if len(summary.robot) else 0.0
        return Track.of([(start, x, y)])
    return None


def chase_outcome(summary, ball, reach):
    """Whether and when the robot came within reach of the ball, from the recorded poses."""
    start = summary.clock[0] if summary.clock else (summary.robot.t[0] if len(summary.robot) else 0.0)
    if not len(summary.robot) or ball is None:
        return Outcome(False, None, None, start)
    gaps = np.hypot(*(summary.robot.points() - ball.at(summary.robot.t)).T)
    within = np.flatnonzero(gaps <= reach)
    if within.size:
        return Outcome(True, float(summary.robot.t[within[0]] - start), float(gaps.min()), start)
    return Outcome(False, None, float(gaps.min()), start)


@dataclass
class RunFacts:
    """What the demo knows that a bag does not: wall time, and its own verdict."""
    wall_seconds: Optional[float] = None
    sim_seconds: Optional[float] = None         # sim time that passed in wall_seconds
    reached: Optional[bool] = None
    detail: str = ''


@dataclass
class Report:
    outcome: Outcome
    frame: object                              # overhead.MapFrame of trajectory.png
    ball: Optional[Track]
    notes: List[str]
    files: List[str]


def write_report(summary, out_dir, world_path=None, ball_name='white_ball', reach=REACH_M,
                 run=None):
    """Write trajectory.png, first_sight.png (if the ball was seen) and summary.md."""
    os.makedirs(out_dir, exist_ok=True)
    notes = list(summary.notes)
    world_map = load_world_map(world_path, notes)
    ball = ball_track(summary, world_map, ball_name)
    if not len(summary.ball) and ball is not None:
        notes.append('the ball is drawn where the world file puts it')
    outcome = chase_outcome(summary, ball, reach)
    files = []
    ball_radius = world_map.balls.get(ball_name, (0.0, 0.0, 0.1))[2]
    image, frame = render_trajectory(summary, world_map, ball, ball_radius)
    _write_png(os.path.join(out_dir, 'trajectory.png'), image, files)
    sight = os.path.join(out_dir, 'first_sight.png')
    if summary.first_sight is not None:
        _write_png(sight, summary.first_sight, files)
    elif os.path.exists(sight):
        os.remove(sight)
    text = summary_markdown(summary, world_map, outcome, reach, run or RunFacts(), notes)
    with open(os.path.join(out_dir, 'summary.md'), 'w') as stream:
        stream.write(text)
    files.append(os.path.join(out_dir, 'summary.md'))
    return Report(outcome, frame, ball, notes, files)


def _write_png(path, rgb, files):
    write_png(path, rgb)
    files.append(path)


def _seconds(value):
    return 'unknown' if value is None else '%.1f s' % value


def summary_markdown(summary, world_map, outcome, reach, run, notes):
    """The text of summary.md."""
    reached = outcome.reached if run.reached is None else run.reached
    sim_span = None
    if summary.clock:
        sim_span = summary.clock[1] - summary.clock[0]
    elif len(summary.robot):
        sim_span = float(summary.robot.t[-1] - summary.robot.t[0])
    lines = ['# Chase report', '',
             '- Bag: `%s`' % summary.path,
             '- World: `%s`' % (world_map.path or 'none'),
             '- Outcome: %s' % ('reached' if reached else 'not reached')
             + (' (%s)' % run.detail if run.detail else ''),
             '- Time to reach (robot origin within %.2f m of the ball centre): %s'
             % (reach, _seconds(outcome.time_to_reach) + ' of sim time'
                if outcome.time_to_reach is not None else 'never, in the recorded poses'),
             '- Closest approach: %s' % ('unknown' if outcome.closest is None
                                         else '%.2f m' % outcome.closest),
             '- Path length: %s' % ('%.2f m (from %s)' % (summary.robot.length(), summary.robot_source)
                                    if len(summary.robot) else 'unknown (%s)' % _NO_ROBOT),
             '- Sim time covered: %s' % _seconds(sim_span),
             '- Real-time factor: %s' % _real_time_factor(summary, sim_span, run),
             '- Camera frames: %s' % _frames_line(summary),
             '- First sight of the ball: %s' % first_sight_line(summary, outcome.start_time),
             '', '## Topics in the bag', '', '| topic | type | messages |', '|---|---|---|']
    for topic, (msgtype, count) in sorted(summary.topics.items()):
        lines.append('| `%s` | %s | %d |' % (topic, msgtype, count))
    if not summary.topics:
        lines.append('| (none) | | 0 |')
    lines += ['', '## Notes', '']
    lines += ['- %s' % note for note in notes] or ['- none: the bag holds every topic the report reads']
    return '\n'.join(lines) + '\n'


def _real_time_factor(summary, sim_span, run):
    sim_seconds = sim_span if run.sim_seconds is None else run.sim_seconds
    if run.wall_seconds and sim_seconds is not None:
        return '%.2f (%.1f s of sim time in %.1f s of wall time)' % (
            sim_seconds / run.wall_seconds, sim_seconds, run.wall_seconds)
    if sim_span is None:
        return 'unknown (no sim time in the bag)'
    if summary.bag_span and summary.clock:
        bag_seconds = summary.bag_span[1] - summary.bag_span[0]
        # rosbag stamps with sim time under use_sim_time; then the bag cannot tell wall time.
        if bag_seconds > 0 and abs(bag_seconds - sim_span) > 0.05 * bag_seconds:
            return '%.2f (%.1f s of sim time in %.1f s of wall time)' % (
                sim_span / bag_seconds, sim_span, bag_seconds)
    return 'unknown (the bag is stamped with sim time; the demo reports it)'


def first_sight_line(summary, start_time):
    """When the camera first saw the ball, as far as the recorded frames tell: the recorder
    may keep only some of the camera's frames (chase_demo thins them to --camera-rate)."""
    if summary.first_sight is None:
        return 'not in the recorded frames'
    seen = summary.first_sight_time - start_time
    if summary.before_sight_time is None:
        return ('by %.1f s of sim time: first_sight.png, the first recorded frame, already shows it'
                % seen)
    skipped = summary.first_sight_seq - summary.before_sight_seq - 1
    if skipped == 0:
        return 'at %.1f s of sim time (first_sight.png, the camera\'s first frame that shows it)' % seen
    between = ('between %.1f s and %.1f s of sim time; first_sight.png is the first recorded frame '
               'that shows it, at %.1f s' % (summary.before_sight_time - start_time, seen, seen))
    # Sequence numbers that do not count up say nothing of how many frames were left out.
    return between + (' (%d camera frames before it were not recorded)' % skipped if skipped > 0 else '')


def _frames_line(summary):
    if not summary.camera_topic:
        return 'none recorded'
    return ('%d published (sequence number of the last recorded frame), %d recorded on `%s`'
            % (summary.camera_last_seq, summary.camera_frames, summary.camera_topic))


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='report', description=__doc__.split('\n')[0])
    parser.add_argument('bag', help='ROS 1 bag recorded from flatsim')
    parser.add_argument('--world', default='', help='SDF world the bag was recorded in')
    parser.add_argument('--output', type=arguments.output_folder, default='out',
                        help='folder for the report (created if missing)')
    parser.add_argument('--robot', default=ROBOT_NAME, help='name of the robot model')
    parser.add_argument('--ball', default='white_ball', help='name of the ball model')
    parser.add_argument('--reach', type=arguments.positive, default=REACH_M,
                        help='distance from the robot base to the ball centre that counts as reached (m)')
    return parser.parse_args(argv)


def build(bag, out_dir, world=None, robot=ROBOT_NAME, ball='white_ball', reach=REACH_M, run=None):
    """Read the bag and write the report; notes go to stderr. Returns the Report."""
    summary = read_bag(bag, robot, ball)
    report = write_report(summary, out_dir, world, ball, reach, run)
    for note in report.notes:
        print('report: %s' % note, file=sys.stderr)
    return report, summary


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        report, summary = build(args.bag, args.output, args.world, args.robot, args.ball, args.reach)
    except FlatsimError as err:
        print('report: %s' % err, file=sys.stderr)
        return 1
    print('report: %s (%s)' % (', '.join(report.files),
                               'reached' if report.outcome.reached else 'not reached'))
    return 0 if summary.topics else 1
