"""The commands every studio has (register_builtin_commands): the World tab, the Edit menu,
the time panel and the views. No ROS here."""
from flatsim.pose import Pose
from flatsim.studio.history import DELETE, MOVE, PASTE, SCALE, Edit
from flatsim.studio.model_names import clone_name
from flatsim.studio.protocol import MAX_STEPS, CommandError, Count, Flag, PoseField, Scale, Text

# A paste without a pose lands this far beside the original (m).
PASTE_OFFSET = 0.5


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
