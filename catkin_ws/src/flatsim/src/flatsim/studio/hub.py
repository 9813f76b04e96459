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

Page -> server: see register_builtin_commands(); every request may carry an
"id", which its reply echoes.
No ROS here.
"""
import itertools
import json
import logging
import struct
import time

import numpy as np

from flatsim.errors import FlatsimError
from flatsim.pose import Pose
from flatsim.studio import chase
from flatsim.studio.history import DELETE, MOVE, PASTE, SCALE, Edit, History
from flatsim.studio.protocol import (MAX_REQUEST_BYTES, MAX_REQUEST_NESTING, MAX_STEPS,
                                     PROTOCOL_VERSION, CommandError, CommandRegistry, Count, Flag,
                                     PoseField, Request, Scale, Text, nested_deeper)

# How long an edit lease lasts without a new edit from its holder.
LEASE_SECONDS = 2.0
# The real-time factor is measured over this much wall time, as gzclient averages it.
RTF_WINDOW = 1.0
# Camera images go to the page at most this wide (a panel shows them smaller still).
CAMERA_MAX_WIDTH = 480
JPEG_QUALITY = 80
# A paste without a pose lands this far beside the original (m).
PASTE_OFFSET = 0.5


def dumps(message):
    return json.dumps(message, separators=(',', ':'), allow_nan=False)


def numbered_name(prefix, taken):
    """The first of prefix0, prefix1, ... not in taken."""
    return next(name for name in (prefix + str(number) for number in itertools.count())
                if name not in taken)


def unique_name(base, taken):
    """base itself if free, else the first of base_0, base_1, ... not in taken: how Gazebo
    names a model inserted from a file, and a pasted copy (base NAME_clone)."""
    return base if base not in taken else numbered_name(base + '_', taken)


def clone_name(source, taken):
    """Gazebo's name for a pasted copy: NAME_clone, then NAME_clone_0, NAME_clone_1, ..."""
    return unique_name(source + '_clone', taken)


def camera_frame(sensor, sim_time, pixels):
    """The binary frame for a camera image: header length, JSON header, JPEG (pixels rgb8)."""
    import cv2  # only tabs with the camera panel open pay for it
    height, width = pixels.shape[:2]
    if width > CAMERA_MAX_WIDTH:
        height = max(1, round(height * CAMERA_MAX_WIDTH / width))
        width = CAMERA_MAX_WIDTH
        pixels = cv2.resize(pixels, (width, height), interpolation=cv2.INTER_AREA)
    bgr = cv2.cvtColor(pixels, cv2.COLOR_RGB2BGR) if pixels.ndim == 3 else pixels
    ok, jpeg = cv2.imencode('.jpg', bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    if not ok:
        raise CommandError('the camera image could not be encoded')
    header = dumps({'type': 'camera_image', 'sensor': sensor, 'sim_time': round(sim_time, 4),
                    'width': width, 'height': height}).encode()
    return struct.pack('>I', len(header)) + header + jpeg.tobytes()


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


class Hub:
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

    # -- edit leases -----------------------------------------------------------------
    def take_lease(self, session, model):
        """Make session the one editing model for LEASE_SECONDS, or refuse clearly."""
        now = self.clock()
        held = self.leases.get(model)
        if held is not None and held[0] is not session and held[1] > now:
            raise CommandError('%s is being edited in %s; try again when it is done there'
                               % (model, held[0].label))
        self.leases[model] = (session, now + LEASE_SECONDS)
        if held is None or held[0] is not session:
            self.broadcast(self._leases_message())

    def check_free(self, session, model):
        """Refuse if another page is editing model (without taking it: an Undo is one step)."""
        held = self.leases.get(model)
        if held is not None and held[0] is not session and held[1] > self.clock():
            raise CommandError('%s is being edited in %s; try again when it is done there'
                               % (model, held[0].label))

    def release_lease(self, session, model):
        self.history.close_move(session, model)
        held = self.leases.get(model)
        if held is not None and held[0] is session:
            del self.leases[model]
            self.broadcast(self._leases_message())

    def _expire_leases(self, now):
        expired = [model for model, (_, expiry) in self.leases.items() if expiry <= now]
        for model in expired:
            self.history.close_move(self.leases[model][0], model)
            del self.leases[model]
        if expired:
            self.broadcast(self._leases_message())

    def _leases_message(self):
        return {'type': 'leases',
                'leases': {model: holder.id for model, (holder, _) in self.leases.items()}}

    # -- undo and redo -----------------------------------------------------------------
    def snapshot(self):
        """The world now (WorldAccess.snapshot); the history first drops what was changed
        from outside. Every read of the world goes through here, so that none is missed."""
        snapshot = self.world.snapshot()
        if snapshot.models_key != self.noticed_key:
            self._notice(dict(snapshot.models_key))
            self.noticed_key = snapshot.models_key
        return snapshot

    def _notice(self, identities):
        dropped = self.history.notice(identities)
        if dropped:
            self.log.info('studio: %s changed outside the studio; Undo leaves %s',
                          ', '.join(dropped), 'it' if len(dropped) == 1 else 'them')
            self.broadcast(self._history_message(dropped))

    def _identities(self):
        """model -> identity, read now (without noticing: the history's own change comes first)."""
        return dict(self.world.snapshot().models_key)

    def record(self, edit):
        """An edit the studio just made joins the history, and every page is told."""
        identities = self._identities()
        self.history.record(edit, identities.get(edit.model))
        self._notice(identities)
        self.broadcast(self._history_message())

    def keep(self, model):
        """The model kept for Undo, or None (logged) if it cannot be."""
        try:
            return self.world.keep_model(model)
        except FlatsimError as error:
            self.log.warning('studio: %s cannot be kept for Undo: %s', model, error)
            return None

    def undo_or_redo(self, session, undo):
        self.snapshot()
        edit = self.history.next_undo() if undo else self.history.next_redo()
        if edit is None:
            raise CommandError('there is nothing to %s' % ('undo' if undo else 'redo'))
        self.check_free(session, edit.model)
        step = self.history.undo if undo else self.history.redo
        edit, outcome = step(self.world, lambda model: self._identities().get(model))
        if not outcome.ok:
            raise CommandError('cannot %s %s: %s' % ('undo' if undo else 'redo', edit.label,
                                                     outcome.message))
        if edit.exists_after(undo):
            self.model_names.add(edit.model)
        else:
            self.model_names.discard(edit.model)
        self.log.info('studio: %s: %s %s', session.label, 'Undo' if undo else 'Redo', edit.label)
        self.broadcast(self._history_message())
        return {'edit': edit.label, 'message': '%s %s' % ('Undo' if undo else 'Redo', edit.label)}

    def _history_message(self, dropped=()):
        return dict(self.history.labels(), type='history', dropped=list(dropped))

    def check_model(self, name):
        if name not in self.model_names:
            raise CommandError('there is no model named %r in the world (models: %s)'
                               % (name, ', '.join(sorted(self.model_names)) or 'none'))

    # -- the stream ------------------------------------------------------------------
    def tick(self):
        """Send what changed since the last tick. Does nothing while no page is in sight."""
        watching = self._streaming()
        if not watching:
            return
        now = self.clock()
        snapshot = self.snapshot()
        if snapshot.models_key != self.models_key:
            self._new_scene(snapshot)
        self._send_poses(snapshot)
        self._expire_leases(now)
        if now >= self.next_status or snapshot.paused != self.last_snapshot.paused \
                or snapshot.sim_time < self.last_sim_time:
            self.next_status = now + self.status_period
            self.broadcast(self._status(snapshot, now), watching)
        self.last_snapshot = snapshot
        if self.scans_wanted and now >= self.next_scans:
            self.next_scans = now + self.scan_period
            self._send_scans()
        if now >= self.next_camera:
            self.next_camera = now + self.camera_period
            self._send_camera_images()

    def _new_scene(self, snapshot):
        """Models came or went: every page gets the whole scene, then all poses."""
        self.models_key = snapshot.models_key
        self.model_names = set(snapshot.poses)
        scene = self.world.scene()
        self.cameras = {'%s::%s' % (model['name'], sensor['name']) for model in scene['models']
                        for sensor in model['sensors'] if sensor['kind'] == 'camera'}
        self.scene_text = dumps(dict(scene, type='scene'))
        self.skipped_text = dumps({'type': 'skipped', 'items': self.world.skipped()})
        for session in list(self.sessions.values()):
            self.deliver(session, self.scene_text)
            self.deliver(session, self.skipped_text)
            session.needs_full_poses = True
        gone = [model for model in self.leases if model not in self.model_names]
        for model in gone:
            del self.leases[model]
        if gone:
            self.broadcast(self._leases_message())
        if self.last_snapshot is None:
            self.last_snapshot = snapshot

    def _send_poses(self, snapshot):
        """Only the moving models whose rounded pose changed are turned into JSON."""
        sessions = self._streaming()
        full = [s for s in sessions if s.needs_full_poses]
        rest = [s for s in sessions if not s.needs_full_poses]
        rounded = snapshot.rounded_poses
        last = self.last_moving
        if last is None or last[0] != snapshot.moving or last[1].shape != rounded.shape:
            rows = range(len(snapshot.moving))
        else:
            rows = np.flatnonzero((rounded != last[1]).any(axis=1)).tolist()
        self.last_moving = (snapshot.moving, rounded)
        changed = {snapshot.moving[row]: snapshot.moving_pose(row) for row in rows}
        # Static models move only by hand, and then the snapshot's poses are a new dict.
        if snapshot.static_poses is not self.last_static:
            if self.last_static is not None:
                changed.update({name: pose for name, pose in snapshot.static_poses.items()
                                if self.last_static.get(name) != pose})
            self.last_static = snapshot.static_poses
        link_poses = snapshot.link_poses
        links = {name: poses for name, poses in link_poses.items()
                 if self.last_links.get(name) != poses}
        self.last_links = link_poses
        self.last_poses.update(changed)
        sim_time = round(snapshot.sim_time, 6)
        if full:
            self.last_poses = snapshot.poses
            self.broadcast({'type': 'poses', 'full': True, 'sim_time': sim_time,
                            'models': self.last_poses, 'links': link_poses}, full)
            for session in full:
                session.needs_full_poses = False
        if rest and (changed or links):
            self.broadcast({'type': 'poses', 'sim_time': sim_time, 'models': changed,
                            'links': links}, rest)

    def _status(self, snapshot, now):
        if snapshot.sim_time < self.last_sim_time:
            # Time went back (Reset World): real time starts over with it, as in gzclient.
            self.real_time_start = now
            self.rtf_samples = []
        self.last_sim_time = snapshot.sim_time
        self.rtf_samples = [(w, s) for w, s in self.rtf_samples if now - w <= RTF_WINDOW]
        self.rtf_samples.append((now, snapshot.sim_time))
        wall0, sim0 = self.rtf_samples[0]
        rtf = (snapshot.sim_time - sim0) / (now - wall0) if now - wall0 > 0.05 else 0.0
        return {'type': 'status', 'sim_time': round(snapshot.sim_time, 6),
                'real_time': round(now - self.real_time_start, 3),
                'real_time_factor': round(rtf, 3), 'paused': snapshot.paused,
                'iterations': snapshot.iterations, 'step_size': snapshot.step_size}

    def _update_scan_wish(self):
        wanted = any(s.scans for s in self._streaming())
        if wanted != self.scans_wanted:
            self.scans_wanted = wanted
            self.world.want_scans(wanted)

    def _update_command_wish(self):
        """The simulator records the drive commands robots get, and watches the calls to
        /ball_chaser/command_robot, only while a page in sight shows a chase view."""
        wanted = any(s.chase for s in self._streaming())
        if wanted != self.commands_wanted:
            self.commands_wanted = wanted
            self.world.want_commands(wanted)

    def _send_scans(self):
        scans = [vars(scan) for scan in self.world.scans()]
        self.broadcast({'type': 'scans', 'scans': scans},
                       [s for s in self._streaming() if s.scans])

    def _send_camera_images(self):
        """One render per camera that some page shows, in the camera panel or the chase view."""
        wanted = {}
        for session in self._streaming():
            if session.camera:
                wanted.setdefault(session.camera, ([], []))[0].append(session)
            if session.chase:
                wanted.setdefault(session.chase, ([], []))[1].append(session)
        for sensor, (cameras, chases) in wanted.items():
            image = self.world.camera_image(sensor)
            if image is None:
                continue
            sim_time, pixels = image
            if cameras:
                frame = camera_frame(sensor, sim_time, pixels)
                for session in cameras:
                    self.deliver(session, frame)
            if chases:
                commands = self.world.drive_commands(sensor.rpartition('::')[0], sim_time)
                calls = self.world.service_calls(sim_time)
                frame = chase.chase_frame(sensor, sim_time, pixels, commands, calls)
                for session in chases:
                    self.deliver(session, frame)


def _json_scalar(value):
    return value is None or (isinstance(value, (str, int, float)) and not isinstance(value, bool))


def _outcome(outcome):
    """The reply fields for a WorldAccess Outcome, or CommandError with its message."""
    if not outcome.ok:
        raise CommandError(outcome.message)
    return {'message': outcome.message}


def register_builtin_commands(registry):
    """The commands every studio has: the World tab, the Edit menu, the time panel, the views."""

    @registry.command('set_pose', 'move a model (as /gazebo/set_model_state)',
                      model=Text(), pose=PoseField())
    def set_pose(request):
        hub, session, model, pose = request.hub, request.session, request.args['model'], request.args['pose']
        hub.check_model(model)
        hub.take_lease(session, model)
        # A drag's first pose begins a Move (from where the model is now); the rest join it.
        dragging = hub.history.moving(session, model) is not None
        before = None if dragging else hub.snapshot().poses.get(model)
        reply = _outcome(request.world.set_model_pose(model, pose))
        if dragging:
            hub.history.moved(session, model, None, pose, None)
        elif before is not None:
            hub.record(Edit(MOVE, model, before=Pose(*before), after=pose, mover=session))
        return reply

    @registry.command('scale', 'the Scale tool: a simple shape model (box, cylinder, sphere) '
                      'times scale [sx, sy, sz]; Undo gives it its sizes back',
                      model=Text(), scale=Scale())
    def scale(request):
        hub, model = request.hub, request.args['model']
        hub.check_model(model)
        hub.take_lease(request.session, model)
        before = hub.keep(model)
        reply = _outcome(request.world.scale_model(model, request.args['scale']))
        after = hub.keep(model) if before is not None else None
        if after is not None:
            hub.record(Edit(SCALE, model, kept=after, replaced=before))
        return reply

    @registry.command('delete', 'delete a model (as /gazebo/delete_model); Undo puts it back',
                      model=Text())
    def delete(request):
        hub, model = request.hub, request.args['model']
        hub.check_model(model)
        hub.take_lease(request.session, model)
        kept = hub.keep(model)
        reply = _outcome(request.world.delete_model(model))
        if kept is not None:
            hub.record(Edit(DELETE, model, kept=kept))
        return reply

    @registry.command('paste', 'spawn a copy of a model under Gazebo\'s NAME_clone name '
                      '(as /gazebo/spawn_sdf_model)', model=Text(), pose=PoseField(required=False))
    def paste(request):
        hub, source = request.hub, request.args['model']
        hub.check_model(source)
        pose = request.args.get('pose')
        if pose is None:
            x, y, z, roll, pitch, yaw = hub.last_poses.get(source, [0.0] * 6)
            pose = Pose(x + PASTE_OFFSET, y + PASTE_OFFSET, z, roll, pitch, yaw)
        name = clone_name(source, hub.model_names)
        reply = _outcome(request.world.copy_model(source, name, pose))
        # Known at once, so that a second paste right after names its copy anew.
        hub.model_names.add(name)
        kept = hub.keep(name)
        if kept is not None:
            hub.record(Edit(PASTE, name, kept=kept))
        reply['name'] = name
        return reply

    @registry.command('undo', 'Edit > Undo: undo the last insert, paste, delete, move or scale, as the '
                      'simulator\'s own change')
    def undo(request):
        return request.hub.undo_or_redo(request.session, undo=True)

    @registry.command('redo', 'Edit > Redo: do again what Undo undid')
    def redo(request):
        return request.hub.undo_or_redo(request.session, undo=False)

    @registry.command('lease', 'start editing a model: other windows are refused until released',
                      model=Text())
    def lease(request):
        request.hub.check_model(request.args['model'])
        request.hub.take_lease(request.session, request.args['model'])

    @registry.command('release', 'done editing a model', model=Text())
    def release(request):
        request.hub.release_lease(request.session, request.args['model'])

    @registry.command('pause', 'pause physics (as /gazebo/pause_physics)')
    def pause(request):
        return _outcome(request.world.pause())

    @registry.command('play', 'run physics (as /gazebo/unpause_physics)')
    def play(request):
        return _outcome(request.world.play())

    @registry.command('step', 'advance physics by count steps while paused',
                      count=Count(1, MAX_STEPS, required=False))
    def step(request):
        return _outcome(request.world.step(request.args.get('count', 1)))

    @registry.command('reset_model_poses', 'Edit > Reset Model Poses (as /gazebo/reset_world)')
    def reset_model_poses(request):
        return _outcome(request.world.reset_model_poses())

    @registry.command('reset_world', 'Edit > Reset World: poses and time '
                      '(as /gazebo/reset_simulation)')
    def reset_world(request):
        return _outcome(request.world.reset_world())

    @registry.command('camera', 'send this page a camera\'s images (sensor "model::sensor"), '
                      'or stop', sensor=Text(required=False), on=Flag())
    def camera(request):
        session = request.session
        if not request.args['on']:
            session.camera = None
            return None
        sensor = request.args.get('sensor')
        if sensor is None:
            raise CommandError('camera needs sensor ("model::sensor") to turn it on')
        if sensor not in request.hub.cameras:
            raise CommandError('there is no camera %r in the world (cameras: %s)'
                               % (sensor, ', '.join(sorted(request.hub.cameras)) or 'none'))
        session.camera = sensor
        request.hub.next_camera = 0.0
        return None

    @registry.command('chase', 'send this page what a ball chaser works with, from a camera '
                      '(sensor "model::sensor"): its ball pixels by third and its drive commands; '
                      'or stop', sensor=Text(required=False), on=Flag())
    def chase_view(request):
        session, hub = request.session, request.hub
        if not request.args['on']:
            session.chase = None
            hub._update_command_wish()
            return None
        sensor = request.args.get('sensor')
        if sensor is None:
            raise CommandError('chase needs sensor ("model::sensor") to turn it on')
        if sensor not in hub.cameras:
            raise CommandError('there is no camera %r in the world (cameras: %s)'
                               % (sensor, ', '.join(sorted(hub.cameras)) or 'none'))
        session.chase = sensor
        hub._update_command_wish()
        hub.next_camera = 0.0
        return None

    @registry.command('stream', 'send this page poses, status, rays and images (it is in sight), '
                      'or stop (it is hidden)', on=Flag())
    def stream(request):
        session = request.session
        if request.args['on'] and not session.streaming:
            session.needs_full_poses = True
        session.streaming = request.args['on']
        request.hub._update_scan_wish()
        request.hub._update_command_wish()
        return None

    @registry.command('scans', 'send this page the lidars\' rays, or stop', on=Flag())
    def scans(request):
        request.session.scans = request.args['on']
        request.hub._update_scan_wish()
        return None
