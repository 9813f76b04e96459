"""A few seconds of bench/bench_load.py's load: /cmd_vel at 1 kHz and drive_bot's
service at 500 calls/s against a running world. The nodes must survive it: still
the same processes, still answering, model states finite, memory roughly flat.
How fast they answer is the bench's business, not the test's.
"""
import pathlib
import sys

import pytest

from rosproc import RosSystem, run_forked

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / 'bench'))
import bench_load  # noqa: E402

LOAD_SECONDS = 6.0
# Generous: a leak of the load's size (thousands of messages a second) would exceed it.
RSS_GROWTH_FACTOR = 1.25
RSS_GROWTH_KIB = 20 * 1024


@pytest.fixture(scope='module')
def figures(tmp_path_factory):
    with RosSystem(tmp_path_factory.mktemp('load')) as ros:
        bench_load.start_system(ros)
        result = run_forked(bench_load.run_load, ros.master_uri, LOAD_SECONDS)
        result['launch_log'] = ros.log_tail('world') + ros.log_tail('drive_bot')
        result['still_running'] = ros.alive('world') and ros.alive('drive_bot')
        yield result


def test_load_was_applied(figures):
    assert figures['cmd_vel_rate'] > 0 and figures['call_rate'] > 0
    assert figures['cmd_vel_errors'] == 0


def test_every_service_call_under_load_was_answered(figures):
    assert figures['call_errors'] == 0


@pytest.mark.parametrize('node', bench_load.LOADED_NODES)
def test_nodes_survive_the_load(figures, node):
    pid_before, _ = figures['rss_before'][node]
    pid_after, _ = figures['rss_after'][node]
    assert pid_before is not None and pid_after == pid_before, figures['launch_log']
    assert figures['still_running']


def test_nodes_answer_after_the_load(figures):
    assert figures['answers_after'] == {'drive_bot': True, 'flatsim': True}


def test_model_states_stay_finite(figures):
    assert all(figures['finite_states'].values()), figures['finite_states']


@pytest.mark.parametrize('node', bench_load.LOADED_NODES)
def test_memory_stays_roughly_flat(figures, node):
    _, before = figures['rss_before'][node]
    _, after = figures['rss_after'][node]
    assert after <= before * RSS_GROWTH_FACTOR + RSS_GROWTH_KIB, \
        '%s grew from %d KiB to %d KiB' % (node, before, after)
