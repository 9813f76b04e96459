"""A submission's own service type, read from its .srv file as text: never imported.

A drive_bot whose DriveToTarget answers with other fields than the course's
(`float64 linear_x_out` and `float64 angular_z_out` for `string msg_feedback`)
still takes the course's request. The grader calls such a service, and serves
its counting stand-in, with the submission's own type, built here:

  read_definition(root, package, type_name)  the .srv beside the chaser's nodes, parsed
  parse_srv(text, type_name)                 its fields, and the md5 a service of it has
  has_course_request(definition)             float64 linear_x, float64 angular_z, in order
  service_class(definition)                  request, response and service classes (genpy)
  definition_text(definition)                the rebuilt .srv text (for an extra world)
  answer_text(answer)                        a response's fields, for the evidence

The classes are generated from a text rebuilt out of the parsed fields alone: a
comment or a string constant of the student's file never reaches generated code.
Only the built-in field types are read (a field of another message type would
need that message's own file). Pure: genmsg and genpy, no rospy.
"""
import os
import re
from dataclasses import dataclass

import genmsg
import genmsg.msg_loader
import genmsg.msgs
import genpy.dynamic

from chase_tools.grading.evidence import short
from chase_tools.grading.scratch import read_beneath

COURSE_REQUEST = (('float64', 'linear_x'), ('float64', 'angular_z'))
COURSE_RESPONSE = (('string', 'msg_feedback'),)
# A type name as a service header gives it: package/Name.
TYPE_NAME = re.compile(r'^([A-Za-z][A-Za-z0-9_]*)/([A-Za-z][A-Za-z0-9_]*)$')
NUMBER = re.compile(r'^[-+]?[0-9.]+([eE][-+]?[0-9]+)?$')
SRV_LIMIT = 64 << 10          # a real .srv is a few lines


class ServiceTypeError(Exception):
    """Why the submission's service type could not be read, in words for the report."""


@dataclass(frozen=True)
class ServiceDefinition:
    type_name: str             # package/Name, as the service's header gives it
    request: tuple             # ((type, name), ...) in order
    response: tuple
    request_text: str          # each half rebuilt from its parsed fields and constants
    response_text: str
    md5: str                   # the service's md5, as genmsg computes it for the .srv
    source: str = ''           # where it was read, for the evidence


def fields_text(fields):
    """'float64 linear_x, float64 angular_z'; 'nothing' for no field."""
    return ', '.join('%s %s' % field for field in fields) or 'nothing'


def _half_text(spec, half):
    """The half's text from its parsed fields and constants only; ServiceTypeError for a
    field of a type the grader does not read."""
    lines = []
    for constant in spec.constants:
        if constant.type == 'string' or not NUMBER.match(constant.val_text.strip()):
            raise ServiceTypeError('its %s has the constant %s %s, which the grader does not read'
                                   % (half, constant.type, constant.name))
        lines.append('%s %s=%s' % (constant.type, constant.name, constant.val_text.strip()))
    for kind, name in zip(spec.types, spec.names):
        base, _is_array, _length = genmsg.msgs.parse_type(kind)
        if not genmsg.msgs.is_builtin(base):
            raise ServiceTypeError('its %s has the field %s %s, of a message type the grader does '
                                   'not read' % (half, kind, name))
        lines.append('%s %s' % (kind, name))
    return '\n'.join(lines) + '\n'


def parse_srv(text, type_name, source=''):
    """The ServiceDefinition of a .srv text for a service of type type_name (package/Name);
    ServiceTypeError saying why when it is not one the grader can call."""
    if not isinstance(type_name, str) or not TYPE_NAME.match(type_name):
        raise ServiceTypeError('its type %r is not a package/Name' % (type_name,))
    if '---' not in text:
        raise ServiceTypeError('%s has no --- between request and response' % (source or 'it'))
    try:
        spec = genmsg.msg_loader.load_srv_from_string(genmsg.MsgContext.create_default(), text,
                                                      type_name)
    except (genmsg.InvalidMsgSpec, ValueError) as error:
        raise ServiceTypeError('%s is not a service definition: %s'
                               % (source or 'it', short(str(error)))) from None
    request_text = _half_text(spec.request, 'request')
    response_text = _half_text(spec.response, 'response')
    # The md5 of the rebuilt text: the same fields and constants give the same md5 text.
    clean = genmsg.msg_loader.load_srv_from_string(
        genmsg.MsgContext.create_default(), request_text + '---\n' + response_text, type_name)
    md5 = genmsg.compute_md5(genmsg.MsgContext.create_default(), clean)
    return ServiceDefinition(type_name, tuple(zip(spec.request.types, spec.request.names)),
                             tuple(zip(spec.response.types, spec.response.names)),
                             request_text, response_text, md5, source)


def srv_file(package, type_name):
    """Where in the workspace's src the .srv of type_name lies: the chaser package's srv/."""
    match = TYPE_NAME.match(type_name or '')
    if match is None:
        raise ServiceTypeError('its type %r is not a package/Name' % (type_name,))
    return os.path.join('src', package, 'srv', match.group(2) + '.srv')


def read_definition(workspace, package, type_name, served_md5=None):
    """The ServiceDefinition of the service type type_name, read from the workspace's
    src/PACKAGE/srv/Name.srv as data (no link followed); ServiceTypeError when it cannot be
    read, or when its md5 is not served_md5 (the file is not what runs)."""
    relative = srv_file(package, type_name)
    shown = os.path.relpath(relative, 'src')
    try:
        text = read_beneath(workspace, relative, SRV_LIMIT).decode('utf-8', errors='replace')
    except OSError as error:
        raise ServiceTypeError('%s could not be read (%s)' % (shown, error.strerror or error)) from None
    definition = parse_srv(text, type_name, shown)
    if served_md5 is not None and definition.md5 != served_md5:
        raise ServiceTypeError('%s gives md5 %s, not the md5 %s it is served with'
                               % (shown, definition.md5, served_md5))
    return definition


def definition_text(definition):
    """The rebuilt .srv text: parse_srv of it gives the same definition."""
    return definition.request_text + '---\n' + definition.response_text


def has_course_request(definition):
    """True when the request is the course's: float64 linear_x, float64 angular_z, in order.
    Constants do not count: they are not sent."""
    return definition.request == COURSE_REQUEST


def response_is_course(definition):
    return definition.response == COURSE_RESPONSE


def _message_class(type_name, text):
    return genpy.dynamic.generate_dynamic(type_name, text)[type_name]


def service_class(definition):
    """A service class like genpy's generated ones (_type, _md5sum, _request_class,
    _response_class) for the definition, its messages generated from the rebuilt text."""
    request = _message_class(definition.type_name + 'Request', definition.request_text)
    response = _message_class(definition.type_name + 'Response', definition.response_text)
    name = definition.type_name.split('/')[1]
    return type(name, (object,), {'_type': definition.type_name, '_md5sum': definition.md5,
                                  '_request_class': request, '_response_class': response})


def answer_text(answer):
    """A response's fields as the evidence shows them: msg_feedback's text alone, as it is the
    course's; 'linear_x_out 0.25, angular_z_out -0.35' otherwise."""
    slots = getattr(answer, '__slots__', ())
    if tuple(slots) == ('msg_feedback',):
        return short(answer.msg_feedback)
    return short(', '.join('%s %s' % (slot, getattr(answer, slot)) for slot in slots)) or 'nothing'
