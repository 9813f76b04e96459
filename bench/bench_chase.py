"""The full chase through ROS in lockstep against real time, in one run.

    python bench/bench_chase.py [--trials 6] [--seed 3] [--mode proportional]

flatsim, drive_bot and process_image (ball_chaser.launch) on one master, on
all the CPUs of the machine, chase the same seeded placements of
chase_house.world twice: in lockstep as fast as the nodes answer (what
chase_demo and evaluate do by default), then at a real-time factor of 1
without lockstep (--real-time, as in Gazebo). Each placement starts from
/gazebo/reset_simulation, as in evaluate. Prints, for each pace, the sim
seconds chased per wall second of the trials (reset and placing included,
launching excluded) and how many placements reached the ball. Figures only.
"""
import argparse
import os
import sys
import tempfile

from chase_tools import evaluate
from chase_tools.chase_graph import default_world_file

BASE_PORT = 23700


def run(placements, lockstep, args, log_dir):
    world_file = default_world_file()
    specs = evaluate.worker_specs(placements, [args.mode], 1, args.port, args.seed, args.timeout,
                                  evaluate.REACH_M, lockstep, 0.0 if lockstep else 1.0, world_file,
                                  log_dir)
    return evaluate.run_trials(specs, 1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--trials', type=int, default=6, help='placements chased at each pace')
    parser.add_argument('--seed', type=int, default=3)
    parser.add_argument('--mode', default='proportional', choices=evaluate.MODES)
    parser.add_argument('--timeout', type=float, default=30.0, help='sim seconds before a trial fails')
    parser.add_argument('--port', type=int, default=BASE_PORT, help='master port')
    args = parser.parse_args(argv)
    placements, _notes = evaluate.placements_for(default_world_file(), args.trials, args.seed)
    print('%d placements of seed %d, %s mode, %d CPUs' % (args.trials, args.seed, args.mode, os.cpu_count()))
    print('pace                          sim s    wall s   real-time factor   reached')
    for label, lockstep in (('lockstep, as fast as it goes', True), ('real time, no lockstep', False)):
        with tempfile.TemporaryDirectory() as log_dir:
            results = run(placements, lockstep, args, log_dir)
        errors = [r.error for r in results if r.error]
        sim_s = sum(r.sim_s for r in results)
        wall_s = sum(r.wall_s for r in results)
        print('%-28s %6.1f   %7.1f   %10.2f         %d/%d%s'
              % (label, sim_s, wall_s, sim_s / wall_s if wall_s else 0.0,
                 sum(r.reached for r in results), len(results),
                 '   (%d could not run: %s)' % (len(errors), errors[0]) if errors else ''), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
