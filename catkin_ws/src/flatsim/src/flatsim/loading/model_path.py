"""Where Gazebo looks for models, and what it finds there (the Insert tab's list).

The folders, in the order Gazebo searches them:
  1. GAZEBO_MODEL_PATH, colon separated;
  2. the folders Gazebo's window remembered in ~/.gazebo/gui.ini, under
     [model_paths] filenames= (colon separated): the Model Editor and the
     Building Editor add the folder a model was saved into when it is not on
     the path yet, so that the model shows under Insert the next time;
  3. ~/.gazebo/models;
  4. the models flatsim ships (catkin_ws/src/flatsim/models: ground_plane, sun, and
     stand-ins for the model-database models students' worlds include most, such as
     cafe_table, so that such an include finds them when nothing else on the path does).
Each folder holds one sub-folder per model, with a model.config naming the
model and its SDF file per SDF version. `model://NAME` names the sub-folder
NAME in the first folder that has one.

HOME and GAZEBO_MODEL_PATH are read from the environment at each call. No ROS here.
"""
import configparser
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import List, Optional

from flatsim.authoring.saving import write_atomically

_SOURCE_MODELS = os.path.normpath(os.path.join(os.path.dirname(__file__), '..', '..', '..', 'models'))
MODEL_URI_PREFIX = 'model://'
# The newest SDF that flatsim's world reader (and Gazebo 11) reads.
NEWEST_SDF_VERSION = (1, 7)


def shipped_models():
    """The folder of the models flatsim ships: beside the sources, or in the installed package's share."""
    if os.path.isdir(_SOURCE_MODELS):
        return _SOURCE_MODELS
    try:
        import rospkg
        return os.path.join(rospkg.RosPack().get_path('flatsim'), 'models')
    except Exception:  # noqa: BLE001 - rospkg raises its own and OS errors alike; the source folder is the fallback
        return _SOURCE_MODELS


def gazebo_home():
    return os.path.join(os.path.expanduser('~'), '.gazebo')


def gui_ini_path():
    return os.path.join(gazebo_home(), 'gui.ini')


def _split_paths(text):
    return [entry for entry in (text or '').split(':') if entry]


def gui_ini_model_paths():
    """The folders in ~/.gazebo/gui.ini [model_paths] filenames; none when the file is missing or unreadable."""
    parser = configparser.ConfigParser(interpolation=None, strict=False)
    try:
        with open(gui_ini_path(), encoding='utf-8') as stream:
            parser.read_file(stream)
    except (OSError, UnicodeDecodeError, configparser.Error):
        return []
    return _split_paths(parser.get('model_paths', 'filenames', fallback=''))


def model_path():
    """The folders Gazebo looks for models in, in its order, each once."""
    folders = (_split_paths(os.environ.get('GAZEBO_MODEL_PATH'))
               + gui_ini_model_paths()
               + [os.path.join(gazebo_home(), 'models'), shipped_models()])
    seen = set()
    ordered = []
    for folder in folders:
        key = os.path.normpath(os.path.expanduser(folder))
        if key not in seen:
            seen.add(key)
            ordered.append(key)
    return ordered


def add_to_gui_ini(folder):
    """Remember folder in ~/.gazebo/gui.ini, as Gazebo does for a folder a model was saved into.

    The file and ~/.gazebo are made if missing; every other line is kept as it
    is. Returns False when the folder was there already. An unwritable file
    raises OSError.
    """
    folder = os.path.normpath(os.path.abspath(os.path.expanduser(folder)))
    path = gui_ini_path()
    try:
        with open(path, encoding='utf-8') as stream:
            lines = stream.read().splitlines()
    except FileNotFoundError:
        lines = []
    section_at = None
    filenames_at = None
    for index, line in enumerate(lines):
        stripped = line.strip()
        if stripped.startswith('[') and stripped.endswith(']'):
            if section_at is not None and filenames_at is None:
                break
            section_at = index if stripped[1:-1].strip() == 'model_paths' else None
        elif section_at is not None and stripped.partition('=')[0].strip() == 'filenames':
            filenames_at = index
            break
    if filenames_at is not None:
        current = _split_paths(lines[filenames_at].partition('=')[2].strip())
        if folder in (os.path.normpath(entry) for entry in current):
            return False
        lines[filenames_at] = 'filenames=' + ':'.join(current + [folder])
    elif section_at is not None:
        lines.insert(section_at + 1, 'filenames=' + folder)
    else:
        lines += ['[model_paths]', 'filenames=' + folder]
    os.makedirs(os.path.dirname(path), exist_ok=True)
    write_atomically(path, '\n'.join(lines) + '\n')
    return True


@dataclass(frozen=True)
class ModelEntry:
    """One model folder as the Insert tab shows it."""
    folder: str                 # the model's own folder
    path: str                   # the model path folder it was found in
    name: str                   # model.config <name>, or the folder's name when unreadable
    description: str = ''
    sdf: str = ''               # the SDF file model.config names for the newest usable version
    sdf_version: str = ''
    problem: str = ''           # why the model cannot be used; '' when it can

    @property
    def uri(self):
        return MODEL_URI_PREFIX + os.path.basename(self.folder)


def _version_key(text):
    try:
        return tuple(int(part) for part in text.strip().split('.'))
    except ValueError:
        return ()


def _pick_sdf(config_root):
    """(file name, version) of the <sdf> entry Gazebo would read: the newest it can read."""
    entries = [((elem.text or '').strip(), (elem.get('version') or '').strip())
               for elem in config_root.findall('sdf')]
    entries = [(name, version) for name, version in entries if name]
    if not entries:
        return None
    readable = [entry for entry in entries if _version_key(entry[1]) <= NEWEST_SDF_VERSION]
    return max(readable or entries, key=lambda entry: _version_key(entry[1]))


def read_model_folder(folder, path=''):
    """The ModelEntry for one folder; a malformed folder gets a problem, never an exception."""
    folder = os.path.normpath(folder)
    base = os.path.basename(folder)
    config_path = os.path.join(folder, 'model.config')

    def entry(problem='', **fields):
        fields.setdefault('name', base)
        return ModelEntry(folder=folder, path=path or os.path.dirname(folder), problem=problem, **fields)

    try:
        config = ET.parse(config_path).getroot()
    except FileNotFoundError:
        return entry('no model.config')
    except (OSError, ET.ParseError) as error:
        return entry('model.config cannot be read (%s)' % error)
    name = (config.findtext('name') or '').strip() or base
    description = ' '.join((config.findtext('description') or '').split())
    picked = _pick_sdf(config)
    if picked is None:
        return entry('model.config names no <sdf> file', name=name, description=description)
    sdf_name, version = picked
    sdf_path = os.path.normpath(os.path.join(folder, sdf_name))
    fields = dict(name=name, description=description, sdf=sdf_path, sdf_version=version)
    try:
        root = ET.parse(sdf_path).getroot()
    except FileNotFoundError:
        return entry('%s is missing' % sdf_name, **fields)
    except (OSError, ET.ParseError) as error:
        return entry('%s cannot be read (%s)' % (sdf_name, error), **fields)
    if root.tag != 'sdf':
        return entry('%s has <%s> at its root, not <sdf>' % (sdf_name, root.tag), **fields)
    if root.find('model') is None and root.find('light') is None:
        return entry('%s holds no <model>' % sdf_name, **fields)
    return entry(**fields)


def _is_model_folder(names):
    """A sub-folder (the names in it) counts as a model when it has a model.config or an SDF
    file of its own."""
    return 'model.config' in names or any(name.endswith('.sdf') for name in names)


def list_models(paths=None) -> List[ModelEntry]:
    """Every model folder on the model path (or in paths), in search order, folders sorted by name.

    The same folder name in two places is listed twice; find_model takes the first.
    A folder that cannot be read is listed with the reason as its problem, rather than left
    out: the Insert tab says what it could not show, as the page lists what flatsim skipped.
    A model path folder that does not exist is left out, as Gazebo leaves it.
    """
    models = []
    for path in model_path() if paths is None else paths:
        try:
            names = sorted(os.listdir(path))
        except FileNotFoundError:
            continue
        except OSError as error:
            models.append(ModelEntry(folder=os.path.normpath(path), path=path,
                                     name=os.path.basename(os.path.normpath(path)),
                                     problem='this model path folder cannot be read (%s)'
                                     % (error.strerror or error)))
            continue
        for name in names:
            folder = os.path.join(path, name)
            if not os.path.isdir(folder):
                continue
            try:
                inside = os.listdir(folder)
            except OSError as error:
                models.append(ModelEntry(folder=os.path.normpath(folder), path=path, name=name,
                                         problem='the folder cannot be read (%s)'
                                         % (error.strerror or error)))
                continue
            if _is_model_folder(inside):
                models.append(read_model_folder(folder, path))
    return models


def find_model(name, paths=None) -> Optional[ModelEntry]:
    """The model folder `model://name` names, or None when no folder on the path has that name."""
    if not name or '/' in name or name in ('.', '..'):
        return None
    for path in model_path() if paths is None else paths:
        folder = os.path.join(path, name)
        if os.path.isdir(folder):
            return read_model_folder(folder, path)
    return None


def model_name_from_uri(uri):
    """'NAME' for 'model://NAME' (a trailing slash allowed), None for any other URI."""
    uri = (uri or '').strip()
    if not uri.startswith(MODEL_URI_PREFIX):
        return None
    name = uri[len(MODEL_URI_PREFIX):].rstrip('/')
    return name if name and '/' not in name else None
