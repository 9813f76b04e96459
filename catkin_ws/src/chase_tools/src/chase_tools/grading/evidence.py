"""The log lines behind a failed item: the decisive ones first, each with where it came from.

A failure leaves a trail of symptoms: a node that died because another took
its name prints "process has died" after the line that says why. The report
quotes, in this order, the first line of each kind that decides:

  REQUIRED process [...] has died      roslaunch stopped everything because of it
  new node registered with same name   a second node took the name, the first was shut down
  [FATAL] ...                          the first FATAL
  [ERROR] ... / RLException / CMake Error
  ...: error: ...                      a compiler's (or a tool's) first error
  the last line of each Python traceback, the exception itself

then the other error lines, first ones first (a traceback's other lines left
out). Each line is quoted as `logs/NAME.log:LINE: text`. Pure: no ROS.
"""
import re

DECISIVE = (
    re.compile(r'REQUIRED process \[[^\]]*\] has died'),
    re.compile(r'new node registered with same name'),
    re.compile(r'\[\s*FATAL\s*\]|\bFATAL\b'),
    re.compile(r'\[\s*ERROR\s*\]|\bERROR:|RLException|CMake Error|^\s*ERROR\b'),
    re.compile(r'(^|[\s:])(fatal )?error:'),
)
SECONDARY = re.compile(r'(ERROR|Error|error|Traceback|Exception|exception|FATAL|process has died|'
                       r'No such file|Permission denied|Read-only file system|unreachable|refused)')
TRACEBACK_START = 'Traceback (most recent call last):'
# Terminal colours and window titles that roslaunch writes.
ESCAPES = re.compile(r'\x1b\[[0-9;]*m|\x1b\]2;[^\x07]*\x07')
LIMIT = 12
# The indented lines of a CMake message quoted after its "CMake Error at ..." line.
CMAKE_MESSAGE_LINES = 4


def tracebacks(lines):
    """(start, end) line indices of each Python traceback; end is the exception and its message."""
    spans = []
    start = None
    for index, line in enumerate(lines):
        if line.startswith(TRACEBACK_START):
            start = index
        elif start is not None and line.strip() and not line.startswith((' ', '\t')):
            spans.append((start, index))
            start = None
    return spans


def decisive_lines(text, source, limit=LIMIT):
    """The lines of a log that explain a failure, decisive first, as 'source:LINE: text'."""
    lines = [ESCAPES.sub('', line).rstrip() for line in text.splitlines()]
    chosen = []

    def take(index):
        if index not in chosen and len(chosen) < limit:
            chosen.append(index)

    for pattern in DECISIVE:
        first = next((i for i, line in enumerate(lines) if pattern.search(line)), None)
        if first is not None:
            take(first)
    spans = tracebacks(lines)
    for _start, end in spans:
        take(end)
    # A traceback's own lines (the calls that led to it) are not symptoms of their own.
    inside = {index for start, end in spans for index in range(start, end)}
    seen = {lines[i] for i in chosen}
    for index, line in enumerate(lines):
        if len(chosen) >= limit:
            break
        if SECONDARY.search(line) and line not in seen and index not in inside:
            seen.add(line)
            take(index)
    order = []
    for index in chosen:
        order.append(index)
        if lines[index].startswith('CMake Error'):
            # CMake says what went wrong on the indented lines that follow.
            for follow in range(index + 1, min(index + 1 + CMAKE_MESSAGE_LINES, len(lines))):
                if not (lines[follow].startswith(' ') and lines[follow].strip()):
                    break
                order.append(follow)
    order = list(dict.fromkeys(order))
    return ['%s:%d: %s' % (source, index + 1, lines[index].strip()) for index in order]


def log_lines(path, source, limit=LIMIT):
    """decisive_lines of a log file, indented for an item's evidence; [] if it cannot be read."""
    try:
        with open(path, errors='replace') as stream:
            text = stream.read()
    except OSError:
        return []
    return ['  ' + line for line in decisive_lines(text, source, limit)]


def short(text, limit=80):
    """text on one line, cut to limit characters with '...' where it was longer."""
    text = ' '.join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + '...'
