"""The studio's commands: how a page's request is checked and handed to its handler.

A request is one JSON object, {"type": NAME, "id": ANY, ...fields}. The
registry knows each command's fields and checks them before its handler
runs, so a handler sees only well-formed values; whatever is wrong gets a
reply that says what and how to fix it. Panels add their own commands with
CommandRegistry.add() (or the @registry.command decorator). No ROS here.
"""
import math
import re
from dataclasses import dataclass
from typing import Callable, Dict

from flatsim.pose import Pose

PROTOCOL_VERSION = 1
# Positions beyond this are refused before they reach the simulator (which
# holds models within 100 km of the origin itself, with its own message).
MAX_COORDINATE = 1e6
MAX_NAME_LENGTH = 256
# The most steps one press of Step may ask for: the simulator is held meanwhile. The page's
# steps field (time_panel.js) has the same max.
MAX_STEPS = 1000
# The longest request the studio reads (a Building Editor design of MAX_PARTS walls fits well).
MAX_REQUEST_BYTES = 1 << 20
# Arrays and objects nested deeper than this are refused before the JSON is read: Python's
# reader recurses, a level at a time, into its recursion limit.
MAX_REQUEST_NESTING = 32


# A string, its closing quote optional and nothing given back: one pass over any text (a
# string left open runs to the end, and json.loads then says what is wrong with it).
_JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*+"?', re.DOTALL)
_JSON_BRACKET = re.compile(r'[\[\]{}]')


def nested_deeper(text, limit=MAX_REQUEST_NESTING):
    """Whether a JSON text's arrays and objects nest deeper than limit (brackets inside its
    strings do not count), found without reading it."""
    depth = 0
    for bracket in _JSON_BRACKET.finditer(_JSON_STRING.sub('""', text)):
        depth += 1 if bracket.group() in '[{' else -1
        if depth > limit:
            return True
    return False


class CommandError(Exception):
    """A request that cannot be carried out; the message goes back to the page and the log."""


class Field:
    """A request field: check(value) returns the value to use or raises CommandError."""
    required = True
    hint = 'a value'

    def __init__(self, required=True):
        self.required = required

    def check(self, name, value):
        raise NotImplementedError


class Text(Field):
    hint = 'a non-empty string'

    def check(self, name, value):
        if not isinstance(value, str) or not value or len(value) > MAX_NAME_LENGTH:
            raise CommandError('%s must be %s of at most %d characters'
                               % (name, self.hint, MAX_NAME_LENGTH))
        return value


class Flag(Field):
    hint = 'true or false'

    def check(self, name, value):
        if not isinstance(value, bool):
            raise CommandError('%s must be true or false' % name)
        return value


class Count(Field):
    def __init__(self, low, high, required=True):
        super().__init__(required)
        self.low, self.high = low, high
        self.hint = 'a whole number from %d to %d' % (low, high)

    def check(self, name, value):
        if isinstance(value, bool) or not isinstance(value, int) or not self.low <= value <= self.high:
            raise CommandError('%s must be a whole number from %d to %d'
                               % (name, self.low, self.high))
        return value


def finite_float(value):
    """value as a finite float, or None: not a number, NaN, infinite, or an integer too big for
    a float (JSON has no limit on digits)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _coordinates(name, value, count, words):
    """value as count floats whose first (up to three) are a position near enough the origin."""
    numbers = [finite_float(v) for v in value] if isinstance(value, list) else []
    if len(numbers) != count or None in numbers:
        raise CommandError('%s must be %s' % (name, words))
    if any(abs(v) > MAX_COORDINATE for v in numbers[:3]):
        raise CommandError('%s is too far from the origin (%g m at most)' % (name, MAX_COORDINATE))
    return numbers


class PoseField(Field):
    """[x, y, z, roll, pitch, yaw] in metres and radians, as a Pose."""
    hint = 'six numbers [x, y, z, roll, pitch, yaw]'

    def check(self, name, value):
        return Pose(*_coordinates(name, value, 6, 'six finite numbers [x, y, z, roll, pitch, yaw]'))


class Scale(Field):
    """[sx, sy, sz]: positive factors, as a tuple."""
    hint = 'three positive numbers [sx, sy, sz]'

    def check(self, name, value):
        numbers = [finite_float(v) for v in value] if isinstance(value, list) else []
        if len(numbers) != 3 or None in numbers or min(numbers) <= 0:
            raise CommandError('%s must be three positive numbers [sx, sy, sz]' % name)
        return tuple(numbers)


class Point(Field):
    """[x, y] in metres, a point on the floor, as a tuple."""
    hint = 'two numbers [x, y]'

    def check(self, name, value):
        return tuple(_coordinates(name, value, 2, 'two finite numbers [x, y]'))


class Record(Field):
    """A JSON value read by parse(name, value), which returns what the handler gets or
    raises CommandError: for the editors' designs."""

    def __init__(self, parse, hint, required=True):
        super().__init__(required)
        self.parse = parse
        self.hint = hint

    def check(self, name, value):
        return self.parse(name, value)


@dataclass
class Command:
    name: str
    handler: Callable
    fields: Dict[str, Field]
    summary: str


@dataclass
class Request:
    """What a handler gets: the hub, the asking session and the checked fields."""
    hub: object
    session: object
    args: dict

    @property
    def world(self):
        return self.hub.world


class CommandRegistry:
    """Command name -> handler(request) -> dict of extra reply fields (or None).

    A handler raises CommandError to refuse; its message is the reply.
    """

    def __init__(self):
        self.commands = {}

    def add(self, name, handler, summary='', /, **fields):
        # Positional only, so that a request may have fields called name or summary.
        if name in self.commands:
            raise ValueError('command %r is registered twice' % name)
        self.commands[name] = Command(name, handler, fields, summary)

    def command(self, name, summary='', /, **fields):
        def register(handler):
            self.add(name, handler, summary, **fields)
            return handler
        return register

    def names(self):
        return sorted(self.commands)

    def parse(self, message):
        """(command, checked args) for a decoded message; CommandError if it does not fit."""
        if not isinstance(message, dict):
            raise CommandError('a request must be a JSON object with a "type"')
        name = message.get('type')
        command = self.commands.get(name) if isinstance(name, str) else None
        if command is None:
            raise CommandError('unknown request type %r; the studio knows %s'
                               % (name, ', '.join(self.names())))
        unknown = sorted(set(message) - set(command.fields) - {'type', 'id'})
        if unknown:
            raise CommandError('%s does not take %s' % (name, ', '.join(unknown)))
        args = {}
        for field_name, field in command.fields.items():
            if field_name not in message:
                if field.required:
                    raise CommandError('%s needs %s (%s)' % (name, field_name, field.hint))
                continue
            args[field_name] = field.check(field_name, message[field_name])
        return command, args
