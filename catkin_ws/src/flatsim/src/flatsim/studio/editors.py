"""The studio's Insert tab, Model Editor, Building Editor and File > Save World: the commands
that read Gazebo's model path and write models and worlds to disk.

Where files may go, and nowhere else (flatsim.authoring.saving checks every path):
  - the editors' default folders, made when first saved into: ~/.gazebo/models for the
    Model Editor (always on the model path) and Gazebo's ~/building_editor_models for the
    Building Editor;
  - the folder of the world file that `gazebo WORLD` opened (save_over_world), whose
    File > Save World writes over WORLD;
  - the folders a user picked in a page's folder chooser (pick_folder) during this run: any
    folder in HOME, or elsewhere but / and the system's (flatsim.authoring.saving.SYSTEM_FOLDERS).
Names are plain: a model's or building's folder name and a world file name hold no '/' or '..'
and start with no dot, and a world file name ends in .world. A file or model folder that is
there already is written over only once the page confirms it (overwrite), as Gazebo asks.
A model or building saved into a folder that is not on the model path yet joins it through
~/.gazebo/gui.ini, as Gazebo's save dialog does, so it shows under Insert at once: every page is
sent the new list.
A page's editor holds the model folder it last saved into until it is closed, so a second page
saving a model of the same name there is refused, with the page that holds it.

Commands, page -> server (each answered by a reply):
  model_path                                  -> {paths, models: [{name, folder, path, uri,
                                                  description, problem}]}
  insert {shape | model, at}                  -> {name} (Edit > Undo takes it out again)
  places                                      -> {home, world_file, model_folder, building_folder,
                                                  picked}
  list_folder {path}                          -> {path, parent, folders, files (.world only)}
                                                 (~/.gazebo/models is made if missing, as
                                                 Gazebo makes it when it starts)
  make_folder {path, name}                    -> {path} (a new folder name in path, the
                                                 chooser's New Folder; path as pick_folder takes)
  pick_folder {path}                          -> {folder}
  save_model {name, folder, static, links, overwrite}          -> {saved, folder | exists}
  save_building {name, folder, walls, openings, overwrite}     -> {saved, folder | exists, walls}
  save_world {folder, file, overwrite}        -> {saved, path, notes | exists}
  editor_closed {editor}
and server -> page: model_path {paths, models} after a save changed what Insert lists.
No ROS here.
"""
import contextlib
import os
import xml.etree.ElementTree as ET

from flatsim.authoring import building, model_writer, saving
from flatsim.authoring.sdf_text import pose_text, to_text
from flatsim.errors import AuthoringError
from flatsim.loading.model_path import add_to_gui_ini, list_models, model_path
from flatsim.pose import Pose
from flatsim.studio.history import INSERT, Edit
from flatsim.studio.model_names import numbered_name, unique_name
from flatsim.studio.protocol import (MAX_COORDINATE, CommandError, Flag, Point, Record, Text,
                                     finite_float)

MODEL_EDITOR_FOLDER = os.path.join('.gazebo', 'models')
BUILDING_EDITOR_FOLDER = 'building_editor_models'
EDITOR_TITLES = {'model': 'Model Editor', 'building': 'Building Editor'}
# Gazebo's toolbar shapes: name prefix and size (box x y z, sphere radius, cylinder radius length).
SIMPLE_SHAPES = {'box': ('unit_box_', (1.0, 1.0, 1.0)), 'sphere': ('unit_sphere_', (0.5,)),
                 'cylinder': ('unit_cylinder_', (0.5, 1.0))}
SHAPE_HEIGHT = 0.5
# A folder listing stops here; a design holds at most this many links, walls or openings.
MAX_LISTED = 2000
MAX_PARTS = 500
MATERIAL_TAGS = ('ambient', 'diffuse', 'specular', 'emissive')


def home():
    return os.path.expanduser('~')


@contextlib.contextmanager
def refusals():
    """An AuthoringError (a bad design, name or folder) becomes the page's message."""
    try:
        yield
    except AuthoringError as error:
        raise CommandError(str(error)) from None


def simple_shape_sdf(kind):
    """(name prefix, model.sdf text) of Gazebo's unit box, sphere or cylinder: 1 kg, grey,
    its centre 0.5 m up (the model's pose, as Gazebo's toolbar makes it)."""
    prefix, size = SIMPLE_SHAPES[kind]
    design = model_writer.ModelDesign(prefix.rstrip('_'), [model_writer.LinkDesign(
        [model_writer.Shape(kind, size)], pose=Pose())])
    root = ET.fromstring(model_writer.model_sdf(design))
    model = root.find('model')
    model.insert(0, ET.Element('pose'))
    model[0].text = pose_text(Pose(z=SHAPE_HEIGHT))
    return prefix, to_text(root)


def model_list():
    """What the Insert tab lists: every model folder on the model path, with its problem if any."""
    paths = model_path()
    return {'paths': paths,
            'models': [{'name': entry.name, 'folder': entry.folder, 'path': entry.path,
                        'uri': entry.uri, 'description': entry.description,
                        'problem': entry.problem} for entry in list_models(paths)]}


# -- designs from the page -----------------------------------------------------------

def _object(name, value, keys):
    if not isinstance(value, dict):
        raise CommandError('%s must be an object' % name)
    unknown = sorted(set(value) - set(keys))
    if unknown:
        raise CommandError('%s does not take %s' % (name, ', '.join(unknown)))
    return value


def _items(name, value, keys):
    """(name of the item, item) for each object in the list value, each with only keys."""
    if not isinstance(value, list) or len(value) > MAX_PARTS:
        raise CommandError('%s must be a list of at most %d items' % (name, MAX_PARTS))
    for index, item in enumerate(value):
        where = '%s[%d]' % (name, index)
        yield where, _object(where, item, keys)


def _number(name, value):
    number = finite_float(value)
    if number is None or abs(number) > MAX_COORDINATE:
        raise CommandError('%s must be a finite number within %g, got %.40r'
                           % (name, MAX_COORDINATE, value))
    return number


def _numbers(name, value, count=None):
    if not isinstance(value, list) or (count is not None and len(value) != count) or len(value) > 6:
        raise CommandError('%s must be %s numbers' % (name, count or 'up to 6'))
    return tuple(_number('%s[%d]' % (name, index), item) for index, item in enumerate(value))


def _pose(name, value):
    return None if value is None else Pose(*_numbers(name, value, 6))


def _text(name, value):
    if not isinstance(value, str):
        raise CommandError('%s must be a string' % name)
    return value


def parse_links(name, value):
    """The Model Editor's links: [{name, mass, pose, shapes: [{kind, size, pose, ambient,
    diffuse, specular, emissive}]}] -> [LinkDesign]; values are checked by check_design."""
    links = []
    for where, item in _items(name, value, ('name', 'mass', 'pose', 'shapes')):
        shapes = []
        for at, shape in _items(where + '.shapes', item.get('shapes', []),
                                ('kind', 'size', 'pose') + MATERIAL_TAGS):
            colours = {tag: _numbers('%s.%s' % (at, tag), shape[tag], 4)
                       for tag in MATERIAL_TAGS if tag in shape}
            shapes.append(model_writer.Shape(
                _text(at + '.kind', shape.get('kind')), _numbers(at + '.size', shape.get('size')),
                _pose(at + '.pose', shape.get('pose')) or Pose(), model_writer.Material(**colours)))
        links.append(model_writer.LinkDesign(
            shapes, _text(where + '.name', item.get('name', 'link')),
            _pose(where + '.pose', item.get('pose')), _number(where + '.mass', item.get('mass', 1.0))))
    return links


def parse_walls(name, value):
    """The Building Editor's walls: [{start, end, thickness, height, color, material}]."""
    walls = []
    for where, item in _items(name, value, ('start', 'end', 'thickness', 'height', 'color', 'material')):
        walls.append(building.Wall(
            _numbers(where + '.start', item.get('start'), 2), _numbers(where + '.end', item.get('end'), 2),
            _number(where + '.thickness', item.get('thickness', building.WALL_THICKNESS)),
            _number(where + '.height', item.get('height', building.WALL_HEIGHT)),
            _numbers(where + '.color', item.get('color', list(building.WALL_COLOR)), 4),
            _text(where + '.material', item.get('material', 'Gazebo/Grey'))))
    return walls


def parse_openings(name, value):
    """The Building Editor's doors and windows: [{wall, offset, kind, width, height, elevation}]."""
    openings = []
    for where, item in _items(name, value, ('wall', 'offset', 'kind', 'width', 'height', 'elevation')):
        wall = item.get('wall')
        if isinstance(wall, bool) or not isinstance(wall, int):
            raise CommandError('%s.wall must be the index of a wall' % where)
        openings.append(building.Opening(
            wall, _number(where + '.offset', item.get('offset')),
            _text(where + '.kind', item.get('kind', 'door')),
            _number(where + '.width', item.get('width', building.DOOR_WIDTH)),
            _number(where + '.height', item.get('height', building.DOOR_HEIGHT)),
            _number(where + '.elevation', item.get('elevation', 0.0))))
    return openings


# -- the studio's state for them -------------------------------------------------------

class Editors:
    """Save places, the editors' hold on model folders, and the commands, on one hub.

    world_file: the world that `gazebo WORLD` opened, which Save World writes over and
    whose folder files may go to; '' when the world came from a launch file (Save World
    then asks for a file, as Gazebo's does before the first Save World As).
    """

    def __init__(self, hub, world_file=''):
        self.hub = hub
        self.log = hub.log
        self.world_file = os.path.abspath(world_file) if world_file else ''
        self.save_target = self.world_file
        self.picked = []
        self.held = {}             # real model folder -> (session, editor)
        self.register(hub.registry)

    # -- places ------------------------------------------------------------------------
    def model_folder(self):
        return os.path.join(home(), MODEL_EDITOR_FOLDER)

    def building_folder(self):
        return os.path.join(home(), BUILDING_EDITOR_FOLDER)

    def allowed(self):
        folders = [self.model_folder(), self.building_folder()] + self.picked
        if self.world_file:
            folders.append(os.path.dirname(self.world_file))
        return folders

    # -- holds ------------------------------------------------------------------------
    def check_hold(self, session, folder):
        holder = self.held.get(folder)
        if holder is not None and holder[0] is not session and holder[0].id in self.hub.sessions:
            raise CommandError('%s is being edited in the %s of %s; save under another name, or '
                               'once it is closed there' % (folder, EDITOR_TITLES[holder[1]],
                                                            holder[0].label))

    def hold(self, session, editor, folder):
        self.release(session, editor)
        self.held[folder] = (session, editor)

    def release(self, session, editor):
        for folder, (holder, kind) in list(self.held.items()):
            if (holder is session and kind == editor) or holder.id not in self.hub.sessions:
                del self.held[folder]

    # -- commands ----------------------------------------------------------------------
    def register(self, registry):
        registry.add('model_path', self.on_model_path, 'the models on the model path (the Insert tab)')
        registry.add('insert', self.on_insert, 'Insert: a simple shape (box, sphere, cylinder) or a '
                     'model folder the Insert tab lists, at a point on the floor or at its own pose',
                     shape=Text(required=False), model=Text(required=False), at=Point(required=False))
        registry.add('places', self.on_places, 'where files may be saved now')
        registry.add('list_folder', self.on_list_folder, 'the folders and .world files in a '
                     'folder, for the folder chooser', path=Text(required=False))
        registry.add('make_folder', self.on_make_folder, 'make a new folder name in the folder '
                     'path (the folder chooser\'s New Folder)', path=Text(), name=Text())
        registry.add('pick_folder', self.on_pick_folder, 'let files be saved in this folder (the '
                     'folder chooser\'s choice)', path=Text())
        registry.add('save_model', self.on_save_model, 'the Model Editor\'s Save As',
                     name=Text(), folder=Text(required=False), static=Flag(required=False),
                     overwrite=Flag(required=False),
                     links=Record(parse_links, 'a list of links, each with its shapes'))
        registry.add('save_building', self.on_save_building, 'the Building Editor\'s Save As',
                     name=Text(), folder=Text(required=False), overwrite=Flag(required=False),
                     walls=Record(parse_walls, 'a list of walls'),
                     openings=Record(parse_openings, 'a list of doors and windows', required=False))
        registry.add('save_world', self.on_save_world, 'File > Save World (no fields: over the '
                     'world file) or Save World As (folder and file; an existing file only with '
                     'overwrite)', folder=Text(required=False), file=Text(required=False),
                     overwrite=Flag(required=False))
        registry.add('editor_closed', self.on_editor_closed, 'an editor of this page was closed: '
                     'the model folder it saved into is free again', editor=Text())

    def on_model_path(self, _request):
        return model_list()

    def on_places(self, _request):
        return {'home': home(), 'world_file': self.save_target, 'model_folder': self.model_folder(),
                'building_folder': self.building_folder(), 'picked': list(self.picked)}

    def on_insert(self, request):
        shape, folder = request.args.get('shape'), request.args.get('model')
        if (shape is None) == (folder is None):
            raise CommandError('insert needs shape (%s) or model (a folder the Insert tab lists)'
                               % ', '.join(SIMPLE_SHAPES))
        taken = set(request.hub.snapshot().poses)
        if shape is not None:
            if shape not in SIMPLE_SHAPES:
                raise CommandError('shape must be one of %s, not %r' % (', '.join(SIMPLE_SHAPES), shape))
            prefix, sdf = simple_shape_sdf(shape)
            name, path = numbered_name(prefix, taken), None
        else:
            base, sdf, path = self._listed_model(folder)
            name = unique_name(base, taken)
        outcome = request.world.insert_model(name, sdf, request.args.get('at'), path)
        if not outcome.ok:
            raise CommandError(outcome.message)
        self.hub.model_names.add(name)
        kept = self.hub.keep(name)
        if kept is not None:
            self.hub.record(Edit(INSERT, name, kept=kept))
        self.log.info('studio: %s inserted %s', request.session.label, name)
        return {'name': name, 'message': outcome.message}

    def _listed_model(self, folder):
        """(model name, SDF text, SDF path) of a model folder the Insert tab lists."""
        wanted = os.path.normpath(folder)
        entry = next((entry for entry in list_models() if entry.folder == wanted), None)
        if entry is None:
            raise CommandError('%s is not a model folder on the model path (%s)'
                               % (folder, ':'.join(model_path())))
        if entry.problem:
            raise CommandError('cannot insert %s (%s): %s' % (entry.name, entry.folder, entry.problem))
        try:
            with open(entry.sdf, encoding='utf-8') as stream:
                sdf = stream.read()
            root = ET.fromstring(sdf)
        except (OSError, UnicodeDecodeError, ET.ParseError) as error:
            raise CommandError('cannot insert %s: %s cannot be read (%s)'
                               % (entry.name, entry.sdf, error)) from None
        model = root.find('model')
        if model is None:
            raise CommandError('cannot insert %s: it is a light, and flatsim simulates no lights'
                               % entry.name)
        # Gazebo names the new model as the SDF does, and model.config only when it does not.
        return model.get('name') or entry.name, sdf, entry.sdf

    def on_list_folder(self, request):
        path = request.args.get('path') or home()
        if not os.path.isabs(path):
            raise CommandError('the folder to list must be an absolute path, got %r' % path)
        path = os.path.normpath(path)
        if path == self.model_folder() and not os.path.lexists(path):
            with refusals():
                saving.make_folder(path)
        folders, files = [], []
        try:
            with os.scandir(path) as entries:
                for entry in entries:
                    if entry.is_dir():
                        folders.append(entry.name)
                    elif entry.name.endswith(saving.WORLD_EXTENSION) and entry.is_file():
                        files.append(entry.name)
        except OSError as error:
            raise CommandError('cannot open the folder %s: %s' % (path, error.strerror or error)) from None
        parent = os.path.dirname(path)
        return {'path': path, 'parent': parent if parent != path else None,
                'folders': sorted(folders, key=str.lower)[:MAX_LISTED],
                'files': sorted(files, key=str.lower)[:MAX_LISTED]}

    def on_make_folder(self, request):
        name = request.args['name'].strip()
        if not name or name in ('.', '..') or '/' in name or '\0' in name:
            raise CommandError('a folder name holds no \'/\' and is not empty, . or .., got %r'
                               % request.args['name'])
        with refusals():
            parent = saving.check_pickable_folder(request.args['path'], home())
        path = os.path.join(parent, name)
        try:
            os.mkdir(path)
        except FileExistsError:
            raise CommandError('%s is there already' % path) from None
        except OSError as error:
            raise CommandError('cannot make the folder %s: %s' % (path, error.strerror or error)) from None
        self.log.info('studio: %s made the folder %s', request.session.label, path)
        return {'path': path}

    def on_pick_folder(self, request):
        with refusals():
            path = saving.check_pickable_folder(request.args['path'], home())
        if path not in self.picked:
            self.picked.append(path)
            self.log.info('studio: %s picked the folder %s to save in', request.session.label, path)
        return {'folder': path}

    def on_editor_closed(self, request):
        editor = request.args['editor']
        if editor not in EDITOR_TITLES:
            raise CommandError('editor must be one of %s' % ', '.join(EDITOR_TITLES))
        self.release(request.session, editor)

    # -- saving models -----------------------------------------------------------------
    def on_save_model(self, request):
        args = request.args
        design = model_writer.ModelDesign(args['name'], args['links'], static=args.get('static', False))
        with refusals():
            model_writer.check_design(design)
            config, sdf = model_writer.model_config(design), model_writer.model_sdf(design)
        return self._save_model_folder(
            request, 'model', design.name, args.get('folder') or self.model_folder(),
            lambda folder: model_writer.save_model_files(design.name, config, sdf, self.allowed(),
                                                         folder))

    def on_save_building(self, request):
        args = request.args
        design = building.BuildingDesign(args['name'], args['walls'], args.get('openings', []))
        with refusals():
            building.check_building(design)
            # As the page snaps what is drawn, and again, so that a design from elsewhere is snapped too.
            design = building.check_building(building.snap_design(design))
            config, sdf = building.building_config(design), building.building_sdf(design)
        reply = self._save_model_folder(
            request, 'building', design.name, args.get('folder') or self.building_folder(),
            lambda folder: model_writer.save_model_files(design.name, config, sdf, self.allowed(),
                                                         folder))
        reply['walls'] = [{'start': list(wall.start), 'end': list(wall.end)} for wall in design.walls]
        return reply

    def _save_model_folder(self, request, editor, name, folder, write):
        """Write a model folder NAME under folder with write(folder), as Gazebo's save dialog does."""
        with refusals():
            target = saving.resolve_target(self.allowed(), folder,
                                           model_writer.folder_name(name, editor))
        self.check_hold(request.session, target)
        if os.path.lexists(target) and not os.path.isdir(target):
            raise CommandError('cannot save %s in %s: a file named %s is in the way'
                               % (name, folder, os.path.basename(target)))
        if _has_entries(target) and not request.args.get('overwrite', False):
            return {'saved': False, 'exists': target,
                    'message': 'A model already exists in folder %s. Do you wish to overwrite the '
                               'existing model files?' % target}
        with refusals():
            if os.path.normpath(folder) in (self.model_folder(), self.building_folder()):
                saving.make_folder(folder)
            written = write(folder)
        self.hold(request.session, editor, target)
        message = 'saved in %s' % written
        try:
            if os.path.realpath(folder) not in map(os.path.realpath, model_path()):
                add_to_gui_ini(folder)
        except OSError as error:
            message += ('; %s could not be remembered in ~/.gazebo/gui.ini (%s), so Insert does not '
                        'list it' % (folder, error.strerror or error))
            self.log.warning('studio: %s', message)
        self.log.info('studio: %s: the %s %s', request.session.label, EDITOR_TITLES[editor], message)
        self.hub.broadcast(dict(model_list(), type='model_path'))
        return {'saved': True, 'folder': written, 'message': message}

    # -- saving the world --------------------------------------------------------------
    def on_save_world(self, request):
        folder, file_name = request.args.get('folder'), request.args.get('file')
        if folder is None and file_name is None:
            if not self.save_target:
                raise CommandError('this world has not been saved yet: use File > Save World As '
                                   '(Ctrl+Shift+S) to choose its file')
            folder, file_name = os.path.split(self.save_target)
            asked_over = True
        elif folder is None or file_name is None:
            raise CommandError('save_world needs both folder and file (Save World As), or neither '
                               '(Save World)')
        else:
            # Save World As, as Gazebo's file dialog: an existing file is replaced once confirmed.
            asked_over = request.args.get('overwrite', False)
            with refusals():
                saving.check_world_file_name(file_name)
        with refusals():
            target = saving.resolve_target(self.allowed(), folder, file_name)
        if os.path.isdir(target):
            raise CommandError('cannot save the world as %s: a folder of that name is in the way'
                               % target)
        if os.path.lexists(target) and not asked_over:
            return {'saved': False, 'exists': target,
                    'message': '%s already exists. Do you want to replace it?' % target}
        saved = request.world.world_sdf()
        with refusals():
            path = saving.save_text(self.allowed(), folder, file_name, saved.text)
        self.save_target = path
        self.log.info('studio: %s saved the world in %s%s', request.session.label, path,
                      ''.join('; %s' % note for note in saved.notes))
        return {'saved': True, 'path': path, 'notes': saved.notes,
                'message': 'saved the world in %s' % path}


def _has_entries(folder):
    try:
        with os.scandir(folder) as entries:
            return any(True for _ in entries)
    except OSError:
        return False


def install(hub, world_file=''):
    """The Insert tab's, the editors' and Save World's commands on hub; returns their Editors.
    The hello tells each page the Building Editor's grid, snap radius, defaults and limits,
    which are held here (flatsim.authoring.building) only."""
    hub.greetings['building'] = lambda: building.editor_settings(MAX_PARTS)
    return Editors(hub, world_file)
