"""Time per placement drawn, this checkout's rule against another revision's, in one run.

    python bench/bench_placement.py [--count 40] [--seeds 1 2 3] [--rounds 3] [--baseline main]

Draws --count placements per seed for the project's robot (the robot_description
that my_robot's world.launch sets) in two worlds: the course's chase_house.world,
and a room with two tables on thin legs (4 cm cylinders and 1.5 cm boxes) where
the sight check has the most to do. After one warm-up draw each, the two rules
draw the same placements in turn, --rounds times, so that a change in the
machine's load falls on both alike, and the bench prints the median wall and
CPU time per placement drawn, the ratio of this checkout's CPU time to the
baseline's (the steadier figure on a shared machine), the time to build the
world's free space once, and how many placements the two rules drew differently.

The baseline is chase_tools/placement.py at git revision --baseline (default
main), loaded beside this checkout's. Figures only: nothing here asserts on time.
"""
import argparse
import importlib.util
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.join(HERE, os.pardir)
PLACEMENT = 'catkin_ws/src/chase_tools/src/chase_tools/placement.py'
CHASE_HOUSE = os.path.join(TOP, 'catkin_ws', 'src', 'my_robot', 'worlds', 'chase_house.world')

TABLES = """<?xml version="1.0"?>
<sdf version="1.6"><world name="tables">
  <model name="walls"><static>1</static><link name="l">
    <collision name="n"><pose>0 4.1 0.5 0 0 0</pose><geometry><box><size>10.4 0.2 1</size></box></geometry></collision>
    <collision name="s"><pose>0 -4.1 0.5 0 0 0</pose><geometry><box><size>10.4 0.2 1</size></box></geometry></collision>
    <collision name="e"><pose>5.1 0 0.5 0 0 0</pose><geometry><box><size>0.2 8.4 1</size></box></geometry></collision>
    <collision name="w"><pose>-5.1 0 0.5 0 0 0</pose><geometry><box><size>0.2 8.4 1</size></box></geometry></collision>
  </link></model>
  %s
  <model name="white_ball"><pose>0 3 0.1 0 0 0</pose>
    <link name="l"><collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision></link>
  </model>
</world></sdf>
"""
TABLE = """<model name="table%d"><static>1</static><pose>%r %r 0 0 0 0</pose><link name="l">
    <collision name="top"><pose>0 0 0.74 0 0 0</pose>
      <geometry><box><size>1.6 0.9 0.03</size></box></geometry></collision>
    %s
  </link></model>"""
LEG = '<collision name="leg%d"><pose>%r %r 0.36 0 0 0</pose><geometry>%s</geometry></collision>'
CYLINDER_LEG = '<cylinder><radius>0.02</radius><length>0.72</length></cylinder>'
BOX_LEG = '<box><size>0.015 0.015 0.72</size></box>'


def tables_world():
    tables = []
    for index, (x, y, leg) in enumerate(((-2.0, 1.0, CYLINDER_LEG), (2.0, -1.0, BOX_LEG))):
        legs = ''.join(LEG % (corner, sx * 0.75, sy * 0.4, leg)
                       for corner, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1))))
        tables.append(TABLE % (index, x, y, legs))
    return TABLES % '\n  '.join(tables)


def load_baseline(revision):
    """chase_tools/placement.py at that git revision, as a module of its own."""
    source = subprocess.run(['git', '-C', TOP, 'show', '%s:%s' % (revision, PLACEMENT)],
                            check=True, capture_output=True, text=True).stdout
    with tempfile.NamedTemporaryFile('w', suffix='.py', delete=False) as stream:
        stream.write(source)
    spec = importlib.util.spec_from_file_location('placement_at_' + revision.replace('/', '_'), stream.name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    os.unlink(stream.name)
    return module


def draw(rule, world, robot, count, seeds):
    """(seconds to build the free space, wall and CPU seconds for all the draws, the placements)."""
    radius, ball_z = rule.ball_of(world, 'white_ball')
    start = time.perf_counter()
    space = rule.FreeSpace(world, keep_out={'white_ball', 'my_robot'})
    built, built_cpu = time.perf_counter(), time.process_time()
    places = []
    for seed in seeds:
        places.extend(rule.sample_placements(space, robot, count, seed, radius, ball_z))
    return built - start, time.perf_counter() - built, time.process_time() - built_cpu, places


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--count', type=int, default=40, help='placements per seed')
    parser.add_argument('--seeds', type=int, nargs='+', default=[1, 2, 3])
    parser.add_argument('--rounds', type=int, default=3)
    parser.add_argument('--baseline', default='main', metavar='REV',
                        help='git revision whose placement rule is the "before" (default main)')
    args = parser.parse_args()

    from chase_tools import evaluate, placement
    from flatsim.loading.sdf_world import load_world, parse_world
    baseline = load_baseline(args.baseline)
    robot = evaluate.launched_robot(CHASE_HOUSE)
    worlds = [('chase_house', load_world(CHASE_HOUSE)), ('tables', parse_world(tables_world()))]
    rules = [('before (%s)' % args.baseline, baseline), ('after (this checkout)', placement)]
    placements = args.count * len(args.seeds)
    print('%d placements per world and rule (%d seeds), median of %d rounds\n'
          % (placements, len(args.seeds), args.rounds))
    print('%-12s %-24s %14s %16s %10s %14s' % ('world', 'rule', 'ms/placement', 'CPU ms/placement',
                                                 'CPU ratio', 'free space ms'))
    for world_name, world in worlds:
        figures = {name: ([], [], []) for name, _rule in rules}
        drawn = {}
        for _name, rule in rules:  # warm: numba's kernels and the world's first reading, not counted
            draw(rule, world, robot, 1, args.seeds[:1])
        for _round in range(args.rounds):
            for name, rule in rules:
                build_s, draws_s, draws_cpu_s, places = draw(rule, world, robot, args.count, args.seeds)
                for column, value in zip(figures[name], (build_s, draws_s, draws_cpu_s)):
                    column.append(value)
                drawn[name] = [(p.robot_x, p.robot_y, p.robot_yaw, p.ball_x, p.ball_y) for p in places]
        medians = {name: [statistics.median(column) for column in columns]
                   for name, columns in figures.items()}
        before_cpu = medians[rules[0][0]][2]
        for name, (build_s, draws_s, draws_cpu_s) in medians.items():
            print('%-12s %-24s %14.2f %16.2f %10s %14.1f'
                  % (world_name, name, 1000 * draws_s / placements, 1000 * draws_cpu_s / placements,
                     '%.2fx' % (draws_cpu_s / before_cpu), 1000 * build_s))
        differ = sum(a != b for a, b in zip(*drawn.values()))
        print('%-12s %d of %d placements differ between the rules\n' % ('', differ, placements))
    return 0


if __name__ == '__main__':
    sys.exit(main())
