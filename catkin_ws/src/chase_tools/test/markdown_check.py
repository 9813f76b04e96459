"""What a Markdown renderer makes of the grader's reports, as far as the tests need: which lines
are headings, table rows and text, and which lie inside a fenced code block (CommonMark's rules
for fences and line endings)."""
import re

LINE_ENDINGS = re.compile(r'\r\n|\r|\n')
FENCE_OPENS = re.compile(r'^ {0,3}(`{3,})[^`]*$')
HEADING = re.compile(r'^ {0,3}(#{1,6})(\s|$)')


def blocks(text):
    """[(kind, line)] with kind 'fenced' for a line inside a fenced code block (its fences too),
    'heading1'..'heading6', 'row' for a line that starts a table's cell, else 'text'."""
    found, fence = [], None
    for line in LINE_ENDINGS.split(text):
        if fence is not None:
            found.append(('fenced', line))
            if re.match(r'^ {0,3}`{%d,}\s*$' % len(fence), line):
                fence = None
            continue
        opening = FENCE_OPENS.match(line)
        if opening:
            fence = opening.group(1)
            found.append(('fenced', line))
        elif HEADING.match(line):
            found.append(('heading%d' % len(HEADING.match(line).group(1)), line))
        elif line.lstrip().startswith('|'):
            found.append(('row', line))
        else:
            found.append(('text', line))
    return found


def headings(text, level=1):
    return [line for kind, line in blocks(text) if kind == 'heading%d' % level]


def first_table(text):
    """The rows of the first table, its head and delimiter rows included."""
    rows, started = [], False
    for kind, line in blocks(text):
        if kind == 'row':
            rows.append(line)
            started = True
        elif started:
            break
    return rows


CODE_SPAN = re.compile(r'(?<!`)(`+)(?!`).*?(?<!`)\1(?!`)')


def outside_fences(text, marker):
    """[(kind, line)] of the lines outside any fence that hold marker outside a code span."""
    return [(kind, line) for kind, line in blocks(text)
            if kind != 'fenced' and marker in CODE_SPAN.sub('', line)]
