"""What a submission's world launch asks of the simulator, read the way roslaunch reads it.

The grader starts the simulator itself (launches.Launches.start_simulator), so
that no node of the submission is the simulator or can reach it. It starts it
as the submission's launch would have: with the world file and the private
parameters that the launch gives the simulator node (flatsim's, which
gazebo_ros's empty_world.launch includes, or the gzserver and gazebo
commands). Reading a launch file runs code ($(command ...), $(eval ...), and
xacro for the robot description), so it is read here, in the submission's
sandbox, as the submission's uid:

    python -m chase_tools.grading.launchread PACKAGE LAUNCH_FILE OUT.json

writes OUT.json (a new file):

    {"simulators": [{"node": "/flatsim", "package": "flatsim", "type": "simulator",
                     "params": {"world_name": "...", "paused": false, ...},
                     "args": [...]}],
     "claims": [{"node": "/gazebo", "package": "...", "type": "..."}],
     "use_sim_time": true}

with the simulator nodes the launch would start, each node's private
parameters of a plain type (text, number, truth value), and its command-line
arguments (gzserver and gazebo take the world file there); and the nodes
that would register under a simulator's name (CLAIMED_NAMES) without being
one of those programs. The grader reads
OUT.json as data (parse) and trusts nothing in it but its shape.
"""
import json
import os
import sys

# (package, type) of the nodes that would start a simulator.
SIMULATOR_NODES = {('flatsim', 'simulator'), ('gazebo_ros', 'gzserver'), ('gazebo_ros', 'gazebo')}
# Node names only a simulator registers under: flatsim's, and gzserver's in Gazebo.
CLAIMED_NAMES = ('/flatsim', '/gazebo')
PLAIN = (str, bool, int, float)
MAX_PARAMS = 64
MAX_TEXT = 4096                 # characters of one value: a file name or a number
MAX_ARGS = 32
READ_LIMIT = 1 << 20            # bytes of OUT.json the grader reads
MAX_NESTING = 8                 # levels of arrays and objects in OUT.json


def read(package, launch_file):
    """The OUT.json document of the launch file PACKAGE/LAUNCH_FILE (see the module's text)."""
    import roslaunch.config
    import roslaunch.rlutil
    paths = roslaunch.rlutil.resolve_launch_arguments([package, launch_file])
    config = roslaunch.config.load_config_default(paths, None, verbose=False)
    simulators, claims = [], []
    for node in config.nodes:
        name = (node.namespace or '/') + (node.name or node.type)
        renamed = [arg.split(':=', 1)[1] for arg in (node.args or '').split()
                   if arg.startswith('__name:=')]
        if renamed:
            name = (node.namespace or '/') + renamed[-1]
        if (node.package, node.type) not in SIMULATOR_NODES:
            if name in CLAIMED_NAMES:
                claims.append({'node': name, 'package': node.package, 'type': node.type})
            continue
        prefix = name.rstrip('/') + '/'
        params = {key[len(prefix):]: param.value for key, param in config.params.items()
                  if key.startswith(prefix) and '/' not in key[len(prefix):]
                  and isinstance(param.value, PLAIN)}
        args = [arg for arg in (node.args or '').split() if ':=' not in arg]
        simulators.append({'node': name, 'package': node.package, 'type': node.type,
                           'params': params, 'args': args})
    use_sim_time = config.params.get('/use_sim_time')
    return {'simulators': simulators, 'claims': claims,
            'use_sim_time': use_sim_time.value if use_sim_time is not None else None}


class LaunchReadError(Exception):
    pass


def parse(data):
    """The document the sandbox wrote, checked: {'simulators': [...], 'use_sim_time': ...} with
    only plain values, bounded. LaunchReadError if it is not of that shape."""
    # The grader's side only: what runs in the sandbox imports nothing of the project's.
    from flatsim.studio.protocol import nested_deeper
    try:
        text = data.decode('utf-8')
    except UnicodeDecodeError as error:
        raise LaunchReadError('not JSON: %s' % error) from None
    # Python's JSON reader recurses a level at a time, into its recursion limit.
    if nested_deeper(text, MAX_NESTING):
        raise LaunchReadError('nested deeper than %d levels' % MAX_NESTING)
    try:
        document = json.loads(text)
    except ValueError as error:
        raise LaunchReadError('not JSON: %s' % error) from None
    if not isinstance(document, dict) or not isinstance(document.get('simulators'), list):
        raise LaunchReadError('no list of simulators')
    simulators = []
    for entry in document['simulators'][:MAX_ARGS]:
        if not isinstance(entry, dict):
            raise LaunchReadError('a simulator that is not an object')
        params = entry.get('params') if isinstance(entry.get('params'), dict) else {}
        simulators.append({
            'node': _text(entry.get('node')), 'package': _text(entry.get('package')),
            'type': _text(entry.get('type')),
            'params': {_text(key): value for key, value in list(params.items())[:MAX_PARAMS]
                       if isinstance(value, PLAIN) and _short(value)},
            'args': [_text(arg) for arg in (entry.get('args') or [])[:MAX_ARGS]
                     if isinstance(arg, str)]})
    claims = []
    for entry in (document.get('claims') or [])[:MAX_ARGS]:
        if not isinstance(entry, dict):
            raise LaunchReadError('a claim that is not an object')
        claims.append({key: _text(entry.get(key)) for key in ('node', 'package', 'type')})
    use_sim_time = document.get('use_sim_time')
    return {'simulators': simulators, 'claims': claims,
            'use_sim_time': use_sim_time if isinstance(use_sim_time, bool) else None}


def world_of(simulator):
    """The world file a simulator node of the document names, '' for none: flatsim's
    ~world_name, or the first .world argument of gzserver and gazebo."""
    world = simulator['params'].get('world_name')
    if isinstance(world, str) and world:
        return world
    return next((arg for arg in simulator['args'] if arg.endswith('.world')), '')


def _text(value):
    if not isinstance(value, str):
        raise LaunchReadError('a name that is not text: %r' % (value,))
    return value[:MAX_TEXT]


def _short(value):
    return not isinstance(value, str) or len(value) <= MAX_TEXT


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 3:
        print('usage: python -m chase_tools.grading.launchread PACKAGE LAUNCH_FILE OUT.json',
              file=sys.stderr)
        return 2
    package, launch_file, out = argv
    try:
        document = read(package, launch_file)
    except Exception as error:  # noqa: BLE001 - said to the grader, which notes it
        print('%s could not be read: %s: %s' % (launch_file, type(error).__name__, error), flush=True)
        return 1
    with open(os.open(out, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644), 'w') as stream:
        json.dump(document, stream)
    return 0


if __name__ == '__main__':
    sys.exit(main())
