"""The studio's protocol over any transport: sessions (one per tab), commands and the stream.

The transport (flatsim.studio.server, or a test) calls, never two at once:
    session = hub.connect(transport)   # transport.send_text(str), transport.send_bytes(bytes)
    hub.receive(session, text)         # one request from the page
    hub.tick()                         # at the stream rate, while hub.watched
    hub.disconnect(session)

Server -> page (JSON text frames, each with "type"):
    hello    {protocol, session, label, commands, stream_rate, and what hub.greetings adds:
             building (flatsim.authoring.building.editor_settings) once the editors are installed}
    scene    describe_scene(): {world, camera (the gui camera pose or null), sky, floor,
             models: [...]}, again whenever models come or go
    skipped  {items: [{subject, reason}]}
    poses    {sim_time, models: {name: pose}, links: {model: {link: pose}}}: only what changed
             since the last one, or everything after a scene ("full": true)
    status   {sim_time, real_time, real_time_factor, paused, iterations, step_size}
    leases   {leases: {model: session}}: who is editing what
    history  {undo: [label], redo: [label], dropped: [model]}: what Edit > Undo and Redo would
             do next (first), e.g. "Insert unit_box_0"; dropped: models whose edits just left
             the history, changed from outside the studio (flatsim.studio.history)
    scans    {scans: [{sensor, origin: [x, y, z, yaw], min_angle, max_angle, range_max, ranges}]}
    reply    {id, request, ok, message, ...}: the answer to every request
and binary frames for camera images: a 4-byte big-endian header length, the
header as JSON {type: "camera_image", sensor, sim_time, width, height}, then a JPEG;
and, alike, for the chase view: {type: "chase_image", ...} (flatsim.studio.chase.chase_frame).
A pose is [x, y, z, roll, pitch, yaw] (metres, radians, fixed axes as SDF).
A page out of sight asks for no stream ("stream", on: false): it gets no poses,
status, scans or camera images until it asks again, and then all poses.

Page -> server: see flatsim.studio.hub_commands; every request may carry an
"id", which its reply echoes.
Leases and Undo are in flatsim.studio.hub_edits, the stream in flatsim.studio.hub_stream.
No ROS here.
"""
import itertools
import json
import logging
import time

from flatsim.studio.frames import dumps
from flatsim.studio.history import History
from flatsim.studio.hub_commands import register_builtin_commands
from flatsim.studio.hub_edits import HubEdits
from flatsim.studio.hub_stream import HubStream
from flatsim.studio.protocol import (MAX_REQUEST_BYTES, MAX_REQUEST_NESTING, PROTOCOL_VERSION, CommandError,
                                     CommandRegistry, Request, nested_deeper)


class Session:
    """One page (browser tab) connected to the studio."""

    def __init__(self, number, transport):
        self.id = number
        self.label = 'window %d' % number
        self.transport = transport
        self.camera = None            # the 'model::sensor' whose images this page wants
        self.chase = None             # the 'model::sensor' whose chase view this page shows
        self.scans = False            # whether this page draws lidar rays
        self.streaming = True         # false while the page is out of sight
        self.needs_full_poses = True
        self.send_failed = False      # its transport failed once (logged once)

    def send(self, message):
        self.transport.send_text(dumps(message))


class Hub(HubEdits, HubStream):
    """Sessions, the command registry and the stream, over a WorldAccess."""

    def __init__(self, world, log=None, clock=time.monotonic, stream_rate=40.0,
                 status_rate=4.0, camera_rate=10.0, scan_rate=10.0):
        self.world = world
        self.log = log or logging.getLogger('flatsim.studio')
        self.clock = clock
        self.stream_rate = stream_rate
        self.status_period = 1.0 / status_rate
        self.camera_period = 1.0 / camera_rate
        self.scan_period = 1.0 / scan_rate
        self.registry = CommandRegistry()
        register_builtin_commands(self.registry)
        self.sessions = {}
        self._numbers = itertools.count(1)
        self.leases = {}              # model -> (session, expiry in clock time)
        self.models_key = None
        self.scene_text = None
        self.skipped_text = None
        self.model_names = set()
        self.cameras = set()
        self.last_poses = {}          # model -> pose, as last sent
        self.last_moving = None       # (names, rounded poses) of the moving models, as last sent
        self.last_links = {}
        self.last_static = None       # the static models' poses, as last sent
        self.last_snapshot = None
        self.next_status = self.next_camera = self.next_scans = 0.0
        self.rtf_samples = []         # (wall, sim) over the last RTF_WINDOW
        self.real_time_start = clock()
        self.last_sim_time = 0.0
        self.scans_wanted = False
        # name -> function: more of the hello, what the page needs before it draws (a panel's settings).
        self.greetings = {}
        self.commands_wanted = False
        self.history = History()
        self.noticed_key = None       # the models_key the history last compared itself with

    @property
    def active(self):
        return bool(self.sessions)

    @property
    def watched(self):
        """Whether any open page takes the stream (one in sight)."""
        return any(session.streaming for session in self.sessions.values())

    def _streaming(self):
        return [session for session in list(self.sessions.values()) if session.streaming]

    # -- sessions ------------------------------------------------------------------
    def connect(self, transport):
        session = Session(next(self._numbers), transport)
        self.sessions[session.id] = session
        hello = {'type': 'hello', 'protocol': PROTOCOL_VERSION, 'session': session.id,
                 'label': session.label, 'commands': self.registry.names(),
                 'stream_rate': self.stream_rate}
        hello.update((name, greeting()) for name, greeting in self.greetings.items())
        session.send(hello)
        snapshot = self.snapshot()
        if snapshot.models_key != self.models_key:
            self._new_scene(snapshot)
        else:
            session.transport.send_text(self.scene_text)
            session.transport.send_text(self.skipped_text)
        session.send(self._status(snapshot, self.clock()))
        session.send(self._leases_message())
        session.send(self._history_message())
        self.log.info('studio: %s opened (%d open)', session.label, len(self.sessions))
        return session

    def disconnect(self, session):
        if self.sessions.pop(session.id, None) is None:
            return
        released = [model for model, (holder, _) in self.leases.items() if holder is session]
        for model in released:
            del self.leases[model]
        self.history.close_move(session)
        if released:
            self.broadcast(self._leases_message())
        self._update_scan_wish()
        self._update_command_wish()
        self.log.info('studio: %s closed (%d open)%s', session.label, len(self.sessions),
                      '; it was editing %s' % ', '.join(released) if released else '')

    def broadcast(self, message, sessions=None):
        text = dumps(message)
        for session in list(self.sessions.values()) if sessions is None else sessions:
            self.deliver(session, text)

    def deliver(self, session, item):
        """Send text (str) or a binary frame (bytes) to one page. A page whose transport fails
        is logged (once) and the others still get theirs: one broken tab never stops the stream."""
        try:
            if isinstance(item, str):
                session.transport.send_text(item)
            else:
                session.transport.send_bytes(item)
        except Exception as error:  # noqa: BLE001 - any transport's failure is one page's
            if not session.send_failed:
                session.send_failed = True
                self.log.error('studio: %s: a message could not be sent: %r', session.label, error,
                               exc_info=True)

    # -- requests --------------------------------------------------------------------
    def receive(self, session, text):
        """Handle one request; the page always gets a reply, and nothing raises out of here."""
        request_id = None
        name = None
        try:
            if len(text) > MAX_REQUEST_BYTES:
                raise CommandError('the request is %d characters long, more than the %d the '
                                   'studio reads' % (len(text), MAX_REQUEST_BYTES))
            if nested_deeper(text):
                raise CommandError('the request is nested too deeply to read (more than %d '
                                   'levels)' % MAX_REQUEST_NESTING)
            try:
                message = json.loads(text)
            except (ValueError, TypeError):
                raise CommandError('the request is not JSON: %.80r' % (text,)) from None
            if isinstance(message, dict):
                request_id = message.get('id')
                name = message.get('type')
            command, args = self.registry.parse(message)
            extra = command.handler(Request(self, session, args)) or {}
        except CommandError as error:
            self.log.warning('studio: %s: %s refused: %s', session.label, name or 'request', error)
            self._reply(session, request_id, name, False, str(error))
            return
        except Exception as error:  # noqa: BLE001 - a bug in one handler must not end the studio
            self.log.error('studio: %s: %s failed: %r', session.label, name, error, exc_info=True)
            self._reply(session, request_id, name, False, 'the studio could not do this: %s' % error)
            return
        self._reply(session, request_id, name, True, extra.pop('message', ''), extra)

    def _reply(self, session, request_id, request, ok, message, extra=None):
        reply = dict(extra or {})
        reply.update(type='reply', id=request_id if _json_scalar(request_id) else None,
                     request=request if isinstance(request, str) else None, ok=ok, message=message)
        session.send(reply)


def _json_scalar(value):
    return value is None or (isinstance(value, (str, int, float)) and not isinstance(value, bool))

