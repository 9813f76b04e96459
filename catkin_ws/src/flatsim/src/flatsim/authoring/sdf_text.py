"""Small helpers that write SDF text: numbers that read back exactly, poses, child elements,
and how deep an element goes (what can be written without recursing too deep)."""
import math
import xml.etree.ElementTree as ET


def number(value):
    """The shortest text that reads back as the same float: '1', '0.1', '-2.5e-07'."""
    value = float(value)
    if value == 0.0:
        return '0'
    if value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


def numbers(values):
    return ' '.join(number(value) for value in values)


def pose_text(pose):
    return numbers((pose.x, pose.y, pose.z, pose.roll, pose.pitch, pose.yaw))


def child(parent, tag, text=None, **attributes):
    elem = ET.SubElement(parent, tag, attributes)
    if text is not None:
        elem.text = text
    return elem


def set_pose(elem, pose):
    """Give elem this <pose> (in its parent's frame), replacing any it had and its relative_to."""
    own = elem.find('pose')
    if own is None:
        own = ET.Element('pose')
        elem.insert(0, own)
    own.attrib.clear()
    own.text = pose_text(pose)


def to_text(root, declaration=True):
    """root as indented XML text, with Gazebo's <?xml version='1.0'?> line."""
    ET.indent(root, '  ')
    body = ET.tostring(root, encoding='unicode')
    return ("<?xml version='1.0'?>\n" if declaration else '') + body + '\n'


def is_finite(*values):
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values)


def element_depth(element):
    """How many levels of elements element is, itself included: counted without recursion, as
    ElementTree's writer and roslaunch's reader would recurse a Python call per level."""
    deepest, pending = 0, [(element, 1)]
    while pending:
        found, depth = pending.pop()
        deepest = max(deepest, depth)
        pending.extend((child, depth + 1) for child in found)
    return deepest
