"""flatsim's ~seed and ~real_time_factor as roslaunch passes them on: a value it
cannot run with ends flatsim with one line naming the parameter, never a
traceback; 0 still runs as fast as possible, as docs/interfaces.md says.

All launches share one master; each launch is server_required, so it ends when
flatsim does.
"""
import pytest

from rosproc import RosSystem, wait_until

EXIT_WALL_S = 60.0


@pytest.fixture(scope='module')
def ros(tmp_path_factory):
    with RosSystem(tmp_path_factory.mktemp('flatsim_parameters')) as system:
        yield system


@pytest.mark.parametrize('argument, error', [
    ('seed:=1e30', "~seed must be a whole number from 0 to 4294967295, got '1e30'"),
    ('real_time_factor:=-1', '~real_time_factor must be 0 (as fast as possible) or 0.001 to 1000 '
                             'sim seconds per wall second, got -1'),
    # roslaunch passes these on as strings.
    ('real_time_factor:=nan', "~real_time_factor must be 0 (as fast as possible) or 0.001 to 1000 "
                              "sim seconds per wall second, got 'nan'"),
    ('real_time_factor:=1e308', "got '1e308'"),
])
def test_a_value_flatsim_cannot_run_with_ends_it_with_one_line(ros, argument, error):
    name = argument.replace(':=', '_')
    ros.launch(name, 'flatsim', 'empty_world.launch', argument, 'server_required:=true',
               'gui:=false')
    assert ros.wait_exit(name, wall_timeout=EXIT_WALL_S), ros.log_tail(name)
    log = ros.log_tail(name, chars=10 ** 6)
    assert 'Traceback' not in log, log
    fatal = [line for line in log.splitlines() if '[FATAL]' in line]
    assert len(fatal) == 1 and error in fatal[0], log


def test_a_real_time_factor_of_zero_runs_as_fast_as_possible(ros):
    ros.launch('fast', 'flatsim', 'empty_world.launch', 'real_time_factor:=0', 'seed:=7',
               'gui:=false')
    try:
        said = wait_until(lambda: 'real-time factor as fast as possible'
                          in ros.log_tail('fast', chars=10 ** 6), EXIT_WALL_S)
        assert said and ros.alive('fast'), ros.log_tail('fast')
    finally:
        ros.stop()
