"""The project's own error type and the record of what a loader skipped."""
from dataclasses import dataclass


class FlatsimError(Exception):
    """Any input flatsim cannot use. The message says what and where."""


class ModelFileError(FlatsimError):
    """A world or robot description that cannot be read at all."""

    def __init__(self, message, path=None, line=None):
        self.path = path
        self.line = line
        where = path or '<string>'
        if line is not None:
            where = '%s:%d' % (where, line)
        super().__init__('%s: %s' % (where, message))


@dataclass(frozen=True)
class Skipped:
    """Something a loader met and left out, with the reason a user can act on."""
    subject: str
    reason: str
    verb = 'skipped'               # what flatsim did with it, as a log line says

    def __str__(self):
        return '%s: %s' % (self.subject, self.reason)


@dataclass(frozen=True)
class Adjusted(Skipped):
    """A setting flatsim keeps but changes to one it can run; the reason says to what."""
    verb = 'adjusted'


class AuthoringError(FlatsimError):
    """A model, building or world design, or a place to save it, that flatsim refuses."""
