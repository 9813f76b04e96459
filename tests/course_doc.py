"""docs/course.md as data: its sections, code blocks and command lines.

The page's conventions, which the parser reads:
- a ```bash block is one terminal, opened at the top of this checkout;
- a line that is only a comment annotates the block and is not a command;
- a command runs on while a quote is open or the line ends in a backslash;
- a comment after a command that starts with an arrow (→) lists words the
  command prints, in part.
"""
import dataclasses
import re

ARROW = '→'


@dataclasses.dataclass(frozen=True)
class Command:
    section: str        # the ## heading it is under
    step: str           # the nearest ### heading or bold lead ("**Arm mover.**") before its block
    block: int          # the block's index on the page
    text: str           # the command as the page gives it, without its comment
    expected: tuple     # words it prints, from its "# →" comment
    line: int           # its first line on the page (1-based)


def scan(text):
    """(code, comment, open quote) of shell text: comments start at a # outside quotes after a
    blank and run to the end of their line; the comment returned is the last one."""
    code, comment, quote = [], '', None
    index = 0
    while index < len(text):
        char = text[index]
        if quote:
            if char == quote:
                quote = None
        elif char in '\'"':
            quote = char
        elif char == '#' and (index == 0 or text[index - 1].isspace()):
            end = text.find('\n', index)
            end = len(text) if end < 0 else end
            comment = text[index + 1:end].strip()
            index = end
            continue
        code.append(char)
        index += 1
    return ''.join(code), comment, quote


def _expected(comment):
    if ARROW not in comment:
        return ()
    return tuple(word for word in comment.split(ARROW, 1)[1].split() if word != '...')


_BOLD_LEAD = re.compile(r'^\*\*([^*]+?)\.?\*\*')


def parse(markdown):
    """Every command of the page's bash blocks, in page order."""
    commands = []
    section = step = ''
    block = -1
    in_block = False
    pending = None      # (first line, code so far, comment)
    for number, line in enumerate(markdown.splitlines(), 1):
        if not in_block:
            if line.startswith('```bash'):
                in_block, block = True, block + 1
            elif line.startswith('## '):
                section = step = line[3:].strip()
            elif line.startswith('### '):
                step = line[4:].strip()
            elif _BOLD_LEAD.match(line):
                step = _BOLD_LEAD.match(line).group(1).strip()
            continue
        if line.startswith('```'):
            if pending:
                raise ValueError('docs/course.md line %d: a command is not closed: %s' % (pending[0], pending[1]))
            in_block = False
            continue
        if pending:
            first, code = pending
            code = code + '\n' + line
        else:
            if not line.strip() or line.lstrip().startswith('#'):
                continue
            first, code = number, line
        stripped, comment, quote = scan(code)
        if quote or stripped.rstrip().endswith('\\'):
            pending = (first, code)
            continue
        pending = None
        text = '\n'.join(part.rstrip() for part in stripped.split('\n')).strip()
        commands.append(Command(section, step, block, text, _expected(comment), first))
    return commands
