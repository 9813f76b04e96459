"""What students' own packages use, installed from Debian and working after `source env.sh`:
cv_bridge from a Python node, and image_view on the camera topic."""
import subprocess
import textwrap

from rosproc import RosSystem, wait_until

CV_BRIDGE_NODE = textwrap.dedent('''\
    #!/usr/bin/env python3
    import numpy as np
    from cv_bridge import CvBridge

    bridge = CvBridge()
    rgb = np.zeros((2, 3, 3), np.uint8)
    rgb[0, 1] = (255, 0, 0)
    msg = bridge.cv2_to_imgmsg(rgb, encoding='rgb8')
    bgr = bridge.imgmsg_to_cv2(msg, desired_encoding='bgr8')
    mono = bridge.imgmsg_to_cv2(msg, desired_encoding='mono8')
    print(msg.encoding, msg.width, msg.height, tuple(bgr[0, 1]), mono.shape)
''')


def test_a_python_node_converts_images_with_cv_bridge(tmp_path):
    node = tmp_path / 'process_image.py'
    node.write_text(CV_BRIDGE_NODE)
    node.chmod(0o755)
    result = subprocess.run([str(node)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stderr
    # rgb8 red becomes bgr8 (0, 0, 255): cv_bridge's compiled conversions ran.
    assert result.stdout.split() == ['rgb8', '3', '2', '(0,', '0,', '255)', '(2,', '3)'], result.stdout
    assert 'NumPy' not in result.stderr, result.stderr


def test_image_view_subscribes_to_the_camera_topic(tmp_path):
    topic = '/camera/rgb/image_raw'
    with RosSystem(tmp_path) as ros:
        ros.run('image_view', ['xvfb-run', '-a', 'rosrun', 'image_view', 'image_view',
                               'image:=%s' % topic])

        def subscribed():
            _pubs, subs, _srvs = ros.graph.master().getSystemState()
            return any(name == topic and nodes for name, nodes in subs)

        assert wait_until(subscribed, 60.0), ros.log_tail('image_view')
        assert ros.alive('image_view'), ros.log_tail('image_view')

