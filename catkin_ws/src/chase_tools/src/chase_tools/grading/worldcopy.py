"""The world the simulator loaded, for the grader to read: copied by the submission, read as data.

The grader needs the submission's world (its models' names, the white
ball, the colliders the placements avoid, the map it draws the trials on).
The world file is the one the simulator names on the master, a parameter
any node of the submission can set, and it includes models found through
Gazebo's model path, which names folders of the submission's too. The
grader, running as root, must not open what the submission names: a link
or a path could lead it to a file that only root may read.

So the reading is split in two:

  copy (here, run by the grader inside the run sandbox, as the submission's
      uid, with the simulator's environment and HOME):
          python -m chase_tools.grading.worldcopy WORLD DEST
      copies the world file to DEST/ and, for each model an include names
      (model://NAME, nested includes too), that model folder's model.config
      and SDF file to DEST/models/NAME/; it can read only what the
      submission itself may read;
  snapshot (in the grader): reads DEST as data, without following any link,
      each file and the whole bounded, XML with entity declarations left
      out, model.config naming no file outside its folder, into a folder of
      the grader's own, which it then loads with flatsim's reader and a
      model path of that folder alone.

Pure: no ROS.
"""
import os
import stat
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import List

from chase_tools.grading.scratch import lstat_beneath, open_beneath, read_beneath, write_new

MODELS = 'models'
CONFIG = 'model.config'
FILE_LIMIT = 16 << 20          # bytes of one file
TOTAL_LIMIT = 64 << 20         # bytes of the whole copy
MAX_FILES = 1000
MAX_DEPTH = 20                 # as flatsim's reader: includes in included models
# A document that declares entities can expand without bound when it is parsed.
ENTITY = b'<!ENTITY'


# -- in the sandbox ------------------------------------------------------------------------

def copy(world_file, dest):
    """Copy world_file and the model files its includes name into dest (a new folder);
    the problems met, in words."""
    from flatsim.loading.model_path import find_model, model_name_from_uri
    problems = []
    os.makedirs(os.path.join(dest, MODELS))
    text = _read(world_file, problems)
    if text is None:
        return problems
    _write(os.path.join(dest, world_name(world_file)), text)
    pending, copied = [(text, 0)], set()
    while pending:
        text, depth = pending.pop()
        for uri in _include_uris(text):
            name = model_name_from_uri(uri)
            if name is None or name in copied or depth >= MAX_DEPTH or len(copied) >= MAX_FILES:
                continue
            entry = find_model(name)
            if entry is None or not os.path.isfile(os.path.join(entry.folder, CONFIG)):
                continue
            copied.add(name)
            folder = os.path.join(dest, MODELS, name)
            os.makedirs(folder)
            config = _read(os.path.join(entry.folder, CONFIG), problems)
            if config is None:
                continue
            _write(os.path.join(folder, CONFIG), config)
            relative = os.path.relpath(entry.sdf, entry.folder) if entry.sdf else ''
            if not relative or not _inside(relative):
                continue
            if not _model_file(relative):
                problems.append('%s names %s: not a model file' % (os.path.join(entry.folder, CONFIG),
                                                                   relative))
                continue
            sdf = _read(entry.sdf, problems)
            if sdf is not None:
                os.makedirs(os.path.dirname(os.path.join(folder, relative)), exist_ok=True)
                _write(os.path.join(folder, relative), sdf)
                pending.append((sdf, depth + 1))
    return problems


def world_name(world_file):
    name = os.path.basename(world_file)
    return name if name not in ('', '.', '..') else 'world.world'


def _read(path, problems):
    try:
        with open(path, 'rb') as stream:
            return stream.read(FILE_LIMIT + 1)
    except OSError as error:
        problems.append('%s: %s' % (path, error.strerror or error))
        return None


def _write(path, data):
    with open(path, 'xb') as stream:
        stream.write(data)


def _include_uris(text):
    try:
        root = ET.fromstring(text.lstrip()) if ENTITY not in text else None
    except ET.ParseError:
        return []
    return [] if root is None else [(include.findtext('uri') or '').strip()
                                    for include in root.iter('include')]


def _model_file(relative):
    """False for a name that is the model's folder itself or its model.config: a model.config
    may name anything, and a model file is neither."""
    return os.path.normpath(relative) not in ('.', CONFIG)


def _inside(relative):
    relative = os.path.normpath(relative)
    return not os.path.isabs(relative) and relative != '..' and not relative.startswith('../')


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    for problem in copy(argv[0], argv[1]):
        print(problem, flush=True)
    return 0


# -- in the grader -------------------------------------------------------------------------

@dataclass
class Snapshot:
    """The grader's own copy: the world file in it ('' if none) and its model path."""
    world_file: str = ''
    model_paths: List[str] = field(default_factory=list)
    left_out: List[str] = field(default_factory=list)   # what was not taken, and why


def snapshot(top, relative, dest, world_file):
    """Read top/relative (a copy's folder, written by the submission) into dest (a folder of
    the grader's own that does not exist yet), as data; the Snapshot."""
    taken = Snapshot()
    os.makedirs(os.path.join(dest, MODELS), mode=0o755)
    budget = [TOTAL_LIMIT, MAX_FILES]
    name = world_name(world_file)
    if _take(top, os.path.join(relative, name), os.path.join(dest, name), budget, taken.left_out):
        taken.world_file = os.path.join(dest, name)
    taken.model_paths = [os.path.join(dest, MODELS)]
    models = os.path.join(relative, MODELS)
    for model in _listing(top, models):
        folder = os.path.join(dest, MODELS, model)
        os.mkdir(folder, 0o755)
        config = os.path.join(folder, CONFIG)
        if not _take(top, os.path.join(models, model, CONFIG), config, budget, taken.left_out):
            continue
        for sdf in _sdf_files(config, taken.left_out):
            os.makedirs(os.path.dirname(os.path.join(folder, sdf)), mode=0o755, exist_ok=True)
            _take(top, os.path.join(models, model, sdf), os.path.join(folder, sdf), budget,
                  taken.left_out)
    return taken


def _listing(top, relative):
    """The names of the folders in top/relative (no link followed)."""
    try:
        fd = open_beneath(top, relative, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return []
    try:
        names = sorted(os.listdir(fd))
    finally:
        os.close(fd)
    found = []
    for name in names[:MAX_FILES]:
        try:
            if stat.S_ISDIR(lstat_beneath(top, os.path.join(relative, name)).st_mode):
                found.append(name)
        except OSError:
            continue
    return found


def _take(top, relative, path, budget, left_out):
    """Copy top/relative to path if it is a regular file within the limits; True if it was."""
    shown = relative
    if budget[1] <= 0:
        left_out.append('%s (more than %d files)' % (shown, MAX_FILES))
        return False
    try:
        data = read_beneath(top, relative, min(FILE_LIMIT, budget[0]) + 1)
    except OSError as error:
        if error.errno != 2:
            left_out.append('%s (%s)' % (shown, error.strerror or error))
        return False
    if len(data) > min(FILE_LIMIT, budget[0]):
        left_out.append('%s (larger than the grader reads)' % shown)
        return False
    if ENTITY in data:
        left_out.append('%s (declares XML entities)' % shown)
        return False
    budget[0] -= len(data)
    budget[1] -= 1
    write_new(path, data, mode=0o644)
    return True


def _sdf_files(config, left_out):
    """The files a model.config names, when all of them lie in its folder; else none, and its
    model.config is removed (the model is then left out, and flatsim's reader says so)."""
    try:
        root = ET.parse(config).getroot()
    except ET.ParseError:
        return []
    names = [(element.text or '').strip() for element in root.iter('sdf')]
    names = [os.path.normpath(name) for name in names if name]
    why = ('names a file outside its folder' if not all(_inside(name) for name in names) else
           ', '.join('names %s: not a model file' % name for name in names if not _model_file(name)))
    if not why:
        return sorted(set(names))
    os.remove(config)
    left_out.append('%s (%s)' % (config, why))
    return []


if __name__ == '__main__':
    sys.exit(main())
