"""Checks that an SDF text is what Gazebo reads, against the SDF specification itself.

Two checks, both from Debian's sdformat packages (setup.sh installs them):
  - spec_errors: every element and attribute must be one the SDF description
    files of that version (/usr/share/sdformat12/<version>/*.sdf, the files
    libsdformat reads its specification from) allow at that place; plugin
    contents are free, as in the specification. libsdformat itself only
    warns about unknown elements, so this is the check that catches them.
  - parser_errors: libsdformat12's own check (what `gz sdf -k` runs): unique
    names, frames, joints and the rest of its semantic checks.
No PyPI package does either: python-sdformat accepts unknown elements, and
the schemas sdformat publishes (.xsd) do not compile as shipped.
"""
import ctypes.util
import functools
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

SPEC_ROOT = '/usr/share/sdformat12'
LIBSDFORMAT = 'libsdformat12.so.12'


def spec_available(version):
    return os.path.isfile(os.path.join(SPEC_ROOT, version, 'root.sdf'))


def parser_available():
    try:
        ctypes.CDLL(LIBSDFORMAT)
    except OSError:
        return False
    return True


@functools.lru_cache(maxsize=None)
def _description(version, file_name):
    return ET.parse(os.path.join(SPEC_ROOT, version, file_name)).getroot()


@functools.lru_cache(maxsize=None)
def _allowed(version, file_name, path):
    """(child descriptions by name, attribute names, free content) of the description at path."""
    desc = _description(version, file_name)
    for index in path:
        desc = desc[index]
    children, attributes, free = {}, set(), False
    for index, item in enumerate(desc):
        if item.tag == 'attribute':
            attributes.add(item.get('name'))
        elif item.tag == 'include':
            children[_description(version, item.get('filename')).get('name')] = (item.get('filename'), ())
        elif item.tag == 'element':
            if item.get('copy_data') == 'true':
                free = True
            elif item.get('ref'):
                children[item.get('name')] = (item.get('ref') + '.sdf', ())
            else:
                children[item.get('name')] = (file_name, path + (index,))
    return children, attributes, free


def spec_errors(text, version=None):
    """What in text the SDF specification of its version does not allow; [] when all is allowed."""
    root = ET.fromstring(text)
    version = version or root.get('version')
    errors = []
    pending = [(root, ('root.sdf', ()), '/sdf')]
    while pending:
        elem, (file_name, path), where = pending.pop()
        children, attributes, free = _allowed(version, file_name, path)
        if free:
            continue
        for attribute in elem.attrib:
            if attribute not in attributes:
                errors.append('%s: attribute %r is not in SDF %s' % (where, attribute, version))
        for item in elem:
            name = item.get('name')
            place = '%s/%s%s' % (where, item.tag, "[@name='%s']" % name if name else '')
            if item.tag not in children:
                errors.append('%s: <%s> is not in SDF %s here' % (place, item.tag, version))
            else:
                pending.append((item, children[item.tag], place))
    return errors


CHECK = """
import ctypes, sys
lib = ctypes.CDLL(%r)
lib.cmdCheck.argtypes = [ctypes.c_char_p]
sys.exit(0 if lib.cmdCheck(sys.argv[1].encode()) == 0 else 1)
""" % LIBSDFORMAT


def parser_errors(path):
    """libsdformat's complaints about the file at path; '' when it says the file is valid."""
    done = subprocess.run([sys.executable, '-c', CHECK, path], capture_output=True, text=True, timeout=60)
    if done.returncode == 0:
        return ''
    return (done.stdout + done.stderr).strip() or 'libsdformat refused the file'


def problems(text, folder):
    """Everything either check finds in text (written to folder/checked.sdf); those not installed are left out."""
    found = []
    version = ET.fromstring(text).get('version')
    if spec_available(version):
        found += spec_errors(text)
    if parser_available():
        path = os.path.join(str(folder), 'checked.sdf')
        with open(path, 'w') as stream:
            stream.write(text)
        complaint = parser_errors(path)
        if complaint:
            found.append(complaint)
    return found
