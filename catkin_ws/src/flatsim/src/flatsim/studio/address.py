"""Where gzclient finds the studio of the simulator on the current ROS master.

The simulator writes its page's address, with the token, to
ROS_HOME/studio/<master host>_<port>.json (ROS_HOME defaults to ~/.ros), a
file only its user can read, and removes it when it stops. gzclient reads the
file for its own ROS_MASTER_URI. The simulator's log (which reaches /rosout, and so
every node on the graph) names the address without its token. To open a browser without putting the token
on a command line (which every local user can read), gzclient opens a local
page of the same mode that forwards to the address, as Jupyter does.
No ROS here.
"""
import ipaddress
import json
import os
import tempfile
import urllib.parse

DEFAULT_MASTER_PORT = 11311
LOOPBACK_NAMES = ('localhost', '127.0.0.1', '::1', 'ip6-localhost')
# Where the studio listens unless told otherwise.
LOOPBACK = '127.0.0.1'


def listen_address(value):
    """value (the ~studio_listen parameter, gazebo's --listen) as an IP address to listen on;
    ValueError saying what is wrong if it is none."""
    try:
        if not isinstance(value, str):
            raise ValueError(value)
        return str(ipaddress.ip_address(value.strip()))
    except ValueError:
        raise ValueError('~studio_listen must be an IP address of this machine, such as %s '
                         '(the default) or 0.0.0.0 (every address), got %.60r'
                         % (LOOPBACK, value)) from None


def is_loopback(host):
    return ipaddress.ip_address(host).is_loopback


def exposed_warning(host, port):
    """What to say when the page is served beyond this machine's loopback."""
    return ('the studio listens on %s%s, not only on %s: whoever can reach that address and '
            'has the token can change the world and save files as you. Give the token to no '
            'one, and do this only on a network you trust (or in a container)'
            % (host, ' port %d' % port if port else '', LOOPBACK))


def ros_home():
    return os.environ.get('ROS_HOME') or os.path.join(os.path.expanduser('~'), '.ros')


def master_key(master_uri):
    """A file name for a master URI; the spellings of loopback count as one host."""
    parts = urllib.parse.urlsplit(master_uri or '')
    host = (parts.hostname or 'localhost').lower()
    if host in LOOPBACK_NAMES or host.startswith('127.'):
        host = 'localhost'
    try:
        port = parts.port or DEFAULT_MASTER_PORT
    except ValueError:
        port = DEFAULT_MASTER_PORT
    safe = ''.join(c if c.isalnum() or c in '.-' else '_' for c in host)
    return '%s_%d' % (safe, port)


def studio_dir(home=None):
    return os.path.join(home or ros_home(), 'studio')


def address_path(master_uri, home=None):
    return os.path.join(studio_dir(home), master_key(master_uri) + '.json')


def _write_private(path, text):
    """Write text to path readable by its owner only, replacing it in one step."""
    folder = os.path.dirname(path)
    os.makedirs(folder, mode=0o700, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=folder, prefix='.studio-')
    try:
        os.fchmod(handle, 0o600)
        with os.fdopen(handle, 'w') as out:
            out.write(text)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.unlink(temporary)
        raise


def without_token(url):
    """url without its query (the token): what may go to a log that others read, such as
    /rosout, which every node on the ROS graph can subscribe to."""
    parts = urllib.parse.urlsplit(url)
    return urllib.parse.urlunsplit((parts.scheme, parts.netloc, parts.path or '/', '', ''))


def write_address(path, url, master_uri, pid=None):
    _write_private(path, json.dumps({'url': url, 'master_uri': master_uri,
                                     'pid': os.getpid() if pid is None else pid}))


def read_address(path):
    """{'url', 'master_uri', 'pid'} from the file, or None if there is none readable."""
    try:
        with open(path) as source:
            found = json.load(source)
    except (OSError, ValueError):
        return None
    return found if isinstance(found, dict) and isinstance(found.get('url'), str) else None


def remove_address(path, url):
    """Remove the file if it still holds url (a newer simulator may have replaced it)."""
    found = read_address(path)
    if found is not None and found['url'] == url:
        try:
            os.unlink(path)
        except OSError:
            pass


def write_opener(url, home=None):
    """A local page, readable by its owner only, that forwards the browser to url; its path."""
    path = os.path.join(studio_dir(home), 'open.html')
    quoted = json.dumps(url).replace('<', '\\u003c')
    _write_private(path, '<!DOCTYPE html>\n<meta charset="utf-8">\n<title>flatsim studio</title>\n'
                         '<script>window.location.replace(%s);</script>\n' % quoted)
    return path
