"""The messages, services and action are the originals' definitions: their
md5sums, computed by genmsg for the generated classes, equal the real ones.

Noetic's turtlesim has no action; RotateAbsolute comes from ROS 2's
turtlesim (its definition text is copied unchanged), so its sums are those
genmsg gives that text."""
import pytest

import turtlesim.msg
import turtlesim.srv

REAL_MD5SUMS = {
    'Pose': (turtlesim.msg, '863b248d5016ca62ea2e895ae5265cf9'),
    'Color': (turtlesim.msg, '353891e354491c51aabe32df673fb446'),
    'Spawn': (turtlesim.srv, '0b2d2e872a8e2887d5ed626f2bf2c561'),
    'Kill': (turtlesim.srv, 'c1f3d28f1b044c871e6eff2e9fc3c667'),
    'SetPen': (turtlesim.srv, '9f452acce566bf0c0954594f69a8e41b'),
    'TeleportAbsolute': (turtlesim.srv, 'a130bc60ee6513855dc62ea83fcc5b20'),
    'TeleportRelative': (turtlesim.srv, '9d5c2dcd348ac8f76ce2a4307bd63a13'),
    'RotateAbsoluteAction': (turtlesim.msg, 'a3f59d3f50edbd1ffdb449bbd78da2a0'),
    'RotateAbsoluteActionGoal': (turtlesim.msg, 'da19f9bccca6e83708105d5ee164530f'),
    'RotateAbsoluteActionResult': (turtlesim.msg, '225465d9f20505ce1d5b2ae69ffbf910'),
    'RotateAbsoluteActionFeedback': (turtlesim.msg, 'a58e2d8fab1227c4eb987ff7b1dedfa3'),
    'RotateAbsoluteGoal': (turtlesim.msg, '7328b114b91e2487fcf12e1581a80145'),
    'RotateAbsoluteResult': (turtlesim.msg, 'b808a22d9acab1efdc64ddcf9bf82dfc'),
    'RotateAbsoluteFeedback': (turtlesim.msg, '847d3db17f318f3422fc2baad0c8af66'),
}


@pytest.mark.parametrize('name', sorted(REAL_MD5SUMS))
def test_md5sum_is_the_real_one(name):
    module, md5sum = REAL_MD5SUMS[name]
    generated = getattr(module, name)
    assert generated._type == 'turtlesim/' + name
    assert generated._md5sum == md5sum


def test_spawn_keeps_the_originals_comment():
    assert turtlesim.srv.SpawnRequest._full_text.splitlines()[3] == \
        'string name # Optional.  A unique name will be created and returned if this is empty'
