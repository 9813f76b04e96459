"""rqt_image_view TOPIC opens an image_view window subscribed to TOPIC (in a virtual display here)."""
import os
import shutil
import signal
import subprocess

import pytest

from rosproc import free_port, wait_until


@pytest.mark.skipif(shutil.which('xvfb-run') is None, reason='needs Xvfb')
def test_rqt_image_view_subscribes_to_the_topic_in_a_window():
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % free_port())
    port = env['ROS_MASTER_URI'].rsplit(':', 1)[1]
    core = subprocess.Popen(['roscore', '-p', port], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    viewer = None
    try:
        viewer = subprocess.Popen(['xvfb-run', '-a', 'rqt_image_view', '/rgb_camera/image_raw'],
                                  env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                  start_new_session=True)

        def subscribed():
            out = subprocess.run(['rostopic', 'info', '/rgb_camera/image_raw'], env=env,
                                 capture_output=True, text=True).stdout
            return '/rqt_image_view' in out.split('Subscribers:')[-1]
        assert wait_until(subscribed, 60.0), 'image_view never subscribed to the topic'
        assert viewer.poll() is None
    finally:
        for proc in (viewer, core):
            if proc is not None:
                os.killpg(proc.pid, signal.SIGINT)
                try:
                    proc.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)


def test_without_a_display_it_says_what_to_do():
    env = dict(os.environ)
    env.pop('DISPLAY', None)
    proc = subprocess.run(['rqt_image_view', '/rgb_camera/image_raw'], env=env,
                          capture_output=True, text=True, timeout=30)
    assert proc.returncode == 1
    assert 'xvfb-run -a rqt_image_view /rgb_camera/image_raw' in proc.stderr
