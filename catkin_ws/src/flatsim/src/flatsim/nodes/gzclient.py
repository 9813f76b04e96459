"""gzclient: open Gazebo's window, the running simulator's studio page.

  gzclient                       # what the course types; also rosrun gazebo_ros gzclient

Waits for the simulator (flatsim) on the current ROS master (ROS_MASTER_URI)
to serve its studio, prints the page's address, and opens it in the default
browser when there is a display (without one it says so and carries on).
It then stays up, as a GUI client does, until Ctrl-C or SIGTERM; when the
simulator stops and another starts on the same master, it opens that one.
Not a ROS node: it reads the address the simulator writes for its user
(flatsim.studio.address) and never talks to the master.
"""
import os
import signal
import sys
import time
import urllib.error
import urllib.request
import webbrowser

import rosgraph

from flatsim.studio import address

POLL_SECONDS = 0.05
# How long the address may stay unanswered before the client says what it waits for.
PATIENCE_SECONDS = 2.0


def say(prog, text):
    print('%s: %s' % (prog, text), flush=True)


def pid_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def answers(url):
    """True when the studio at url serves its page."""
    try:
        with urllib.request.urlopen(url, timeout=2.0) as response:
            return response.status == 200
    except (urllib.error.URLError, OSError, ValueError):
        return False


def live_address(path, pid=None):
    """The url in the address file at path if its simulator runs (and is pid, if given)."""
    found = address.read_address(path)
    if found is None or not isinstance(found.get('pid'), int) or not pid_alive(found['pid']):
        return None
    if pid is not None and found['pid'] != pid:
        return None
    return found['url']


def wait_for_studio(path, prog, master_uri, pid=None, still_waiting=lambda: True):
    """Poll until the simulator's studio answers; its url, or None if still_waiting() says stop."""
    started = time.monotonic()
    told = False
    while still_waiting():
        url = live_address(path, pid)
        if url is not None and answers(url):
            return url
        if not told and time.monotonic() - started > PATIENCE_SECONDS:
            say(prog, 'waiting for the simulator on %s (start it with roslaunch, gazebo or '
                      'gzserver)' % master_uri)
            told = True
        time.sleep(POLL_SECONDS)
    return None


def has_display():
    return bool(os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY'))


def open_page(url, prog):
    """Open url in the default browser if there is a display; never fails."""
    if not has_display():
        say(prog, 'no display: open the address above in a browser')
        return False
    try:
        # The browser gets a local page that forwards to the address, so the token is not
        # on a command line that every user of the machine can read.
        opener = address.write_opener(url)
        opened = webbrowser.open('file://' + opener)
    except (OSError, webbrowser.Error) as error:
        say(prog, 'could not open a browser (%s): open the address above yourself' % error)
        return False
    if not opened:
        say(prog, 'found no browser to open: open the address above yourself')
    return opened


def show(url, prog):
    say(prog, 'Gazebo\'s window (flatsim studio) is at %s' % url)
    open_page(url, prog)


class Stop(Exception):
    """SIGINT or SIGTERM: stop, as a GUI client does when its window closes."""


def _stop(_signum, _frame):
    raise Stop()


def install_stop_handlers():
    signal.signal(signal.SIGINT, _stop)
    signal.signal(signal.SIGTERM, _stop)


def watch(path, url, prog, master_uri):
    """Stay up; when the simulator goes, wait for the next one on this master and show it."""
    while True:
        while live_address(path) == url:
            time.sleep(0.5)
        say(prog, 'the simulator stopped; waiting for it to start again')
        url = wait_for_studio(path, prog, master_uri)
        show(url, prog)


def main():
    prog = 'gzclient'
    args = rosgraph.myargv(sys.argv)[1:]
    if any(arg in ('-h', '--help') for arg in args):
        print(__doc__.strip())
        return
    install_stop_handlers()
    master_uri = rosgraph.get_master_uri()
    path = address.address_path(master_uri)
    try:
        url = wait_for_studio(path, prog, master_uri)
        show(url, prog)
        watch(path, url, prog, master_uri)
    except Stop:
        pass
