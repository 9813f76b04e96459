"""Copied work in a class: pairs of submissions whose code is unusually similar. Pure: no ROS.

What teachers know from course autograders (MOSS, JPlag, Gradescope): each
submission's code is fingerprinted, and pairs that share much of it are shown
side by side. Here copydetect does the fingerprinting: it tokenizes the code,
replaces names, strings and comments with placeholders (renaming variables
or rewording comments does not hide a copy), and winnows its k-grams.

A submission's code is the C++ and Python files of the packages the grader
builds (submission.find), or of every package in it when it is incomplete.
Each language's files are fingerprinted together. The code the course hands
every student (course/templates: drive_bot.cpp and process_image.cpp) is
boilerplate: its fingerprints count in no submission. A pair is reported when
at least `threshold` of either one's fingerprinted code is found in the other.

Files are read as data, as the grader reads a submission: no link followed,
each file and the whole bounded. Similarity is evidence for a teacher, never
a grade: nothing here changes one.
"""
import html
import io
import logging
import os
from dataclasses import dataclass, field
from typing import Dict, List, Tuple

from chase_tools.grading import rubric, submission
from chase_tools.grading.scratch import read_beneath

MARKDOWN_FILE = 'similarity.md'
HTML_FILE = 'similarity.html'
# copydetect's defaults: k-grams of 25 filtered characters, every one kept (a window of 1).
NOISE = 25
WINDOW = 1
THRESHOLD = 0.6
LANGUAGES = {'.cpp': 'cpp', '.cc': 'cpp', '.cxx': 'cpp', '.h': 'cpp', '.hpp': 'cpp', '.py': 'python'}
FILE_LIMIT = 256 << 10
TOTAL_LIMIT = 4 << 20
MAX_FILES = 200
TEMPLATES = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, os.pardir,
                         os.pardir, 'course', 'templates')


@dataclass
class Code:
    name: str
    files: Dict[str, List[Tuple[str, str]]] = field(default_factory=dict)   # language -> [(path, text)]
    left_out: List[str] = field(default_factory=list)
    prints: Dict[str, list] = field(default_factory=dict)                    # language -> per file

    def fingerprints(self, language, boilerplate):
        """Each file's fingerprint, the course's code left out. Each file apart, so that no
        k-gram runs from one file into the next (two students' files in the same order would
        share those)."""
        if language not in self.prints:
            from copydetect import CodeFingerprint
            from copydetect.utils import get_token_coverage
            prints = []
            for _path, text in self.files[language]:
                found = CodeFingerprint('code', NOISE, WINDOW, fp=io.StringIO(text), language=language)
                # Left out here rather than by copydetect's own boilerplate argument, which
                # takes the winnowed hashes for unique and then drops the wrong ones.
                for common in found.hashes & boilerplate.get(language, set()):
                    found.hashes.discard(common)
                    del found.hash_idx[common]
                found.token_coverage = get_token_coverage(found.hash_idx, NOISE, len(found.filtered_code))
                prints.append(found)
            self.prints[language] = prints
        return self.prints[language]


@dataclass
class Pair:
    first: str
    second: str
    score: float                     # the larger share of either's code found in the other
    shares: Tuple[float, float]
    language: str
    passages: Tuple[str, str]        # each side's code, matching passages marked (HTML)
    lines: Tuple[List[str], List[str]]   # each side's matching passages, as 'file:first-last'


def code_of(name, path):
    """The Code of the submission in path, read as data."""
    found = submission.find(path)
    packages = ([found.packages[package] for package in found.needed()]
                if found.robot is not None and found.chaser is not None
                else list(found.packages.values()))
    code = Code(name)
    budget = [TOTAL_LIMIT, MAX_FILES]
    top = os.path.realpath(path)
    for package in sorted(packages, key=lambda p: p.name):
        for relative in _source_files(package.path, top):
            language = LANGUAGES[os.path.splitext(relative)[1].lower()]
            text = _read(top, relative, budget, code.left_out)
            if text is not None:
                code.files.setdefault(language, []).append((relative, text))
    return code


def _source_files(package_path, top):
    found = []
    for root, dirs, files in os.walk(package_path):
        dirs[:] = sorted(d for d in dirs if not d.startswith('.') and d not in submission.SKIPPED_DIRS)
        for name in sorted(files):
            if os.path.splitext(name)[1].lower() in LANGUAGES:
                found.append(os.path.relpath(os.path.join(root, name), top))
    return found


def _read(top, relative, budget, left_out):
    if budget[1] <= 0:
        left_out.append('%s (more than %d files)' % (relative, MAX_FILES))
        return None
    try:
        data = read_beneath(top, relative, min(FILE_LIMIT, budget[0]) + 1)
    except OSError as error:
        left_out.append('%s (%s)' % (relative, error.strerror or error))
        return None
    if len(data) > min(FILE_LIMIT, budget[0]):
        left_out.append('%s (larger than %d KiB)' % (relative, FILE_LIMIT >> 10))
        return None
    budget[0] -= len(data)
    budget[1] -= 1
    return data.decode('utf-8', errors='replace')


def boilerplate_hashes(folder=TEMPLATES):
    """{language: {fingerprint}} of the code the course gives every student."""
    from copydetect import CodeFingerprint
    hashes = {}
    for name in sorted(os.listdir(folder)):
        language = LANGUAGES.get(os.path.splitext(name)[1].lower())
        if language is not None:
            hashes.setdefault(language, set()).update(
                CodeFingerprint(os.path.join(folder, name), NOISE, 1, language=language).hashes)
    return hashes


def compare(first, second, boilerplate, threshold=THRESHOLD):
    """The Pair of two Codes when they are alike past threshold in some language, else None."""
    best = None
    for language in sorted(set(first.files) & set(second.files)):
        prints = [code.fingerprints(language, boilerplate) for code in (first, second)]
        shared = set().union(*(p.hashes for p in prints[0])) & set().union(*(p.hashes for p in prints[1]))
        totals = [sum(p.token_coverage for p in side) for side in prints]
        if not shared or min(totals) == 0:
            continue
        matches = [[_matches(p, shared) for p in side] for side in prints]
        shares = tuple(float(sum(covered for covered, _cut in side) / total)
                       for side, total in zip(matches, totals))
        score = max(shares)
        if score < threshold or (best is not None and score <= best.score):
            continue
        sides = list(zip((first, second), prints, matches))
        best = Pair(first.name, second.name, score, shares, language,
                    tuple(_marked(code.files[language], side) for code, _p, side in sides),
                    tuple(_passage_lines(code.files[language], side) for code, _p, side in sides))
    return best


def _matches(found, shared):
    """(tokens of found's file covered by the shared fingerprints, their slices in its text)."""
    import numpy as np
    from copydetect.utils import get_copied_slices, get_token_coverage
    positions = {h: found.hash_idx[h] for h in shared if h in found.hash_idx}
    covered = get_token_coverage(positions, NOISE, len(found.filtered_code))
    if not positions:
        return 0, np.zeros((2, 0), dtype=int)
    cut = get_copied_slices(np.concatenate([np.array(i) for i in positions.values()]), NOISE)
    if len(found.offsets) > 0:
        # From the filtered text back to the file's own, as copydetect's compare_files does.
        cut = cut + found.offsets[:, 1][np.clip(np.searchsorted(found.offsets[:, 0], cut), 0,
                                                found.offsets.shape[0] - 1)]
    return covered, cut


def _marked(files, matches):
    """A side's files as HTML, each after its name, the shared passages marked."""
    from copydetect.utils import highlight_overlap
    parts = []
    for (path, text), (_covered, cut) in zip(files, matches):
        body = (highlight_overlap(text, cut, '<mark>', '</mark>', escape_html=True)[0]
                if cut.shape[1] else html.escape(text))
        parts.append('<b>%s</b>\n%s' % (html.escape(path), body))
    return '\n'.join(parts)


def _passage_lines(files, matches):
    """'file:first-last' for each shared passage of a side."""
    named = []
    for (path, text), (_covered, cut) in zip(files, matches):
        for start, end in zip(cut[0], cut[1]):
            named.append('%s:%d-%d' % (path, text.count('\n', 0, start) + 1,
                                       text.count('\n', 0, max(start, end - 1)) + 1))
    return named


def similar_pairs(codes, known=(), threshold=THRESHOLD, boilerplate=None):
    """Pairs among codes, and of each of codes with each of known, most alike first."""
    logging.getLogger('copydetect').setLevel(logging.ERROR)
    boilerplate = boilerplate_hashes() if boilerplate is None else boilerplate
    candidates = [(a, b) for i, a in enumerate(codes) for b in codes[i + 1:]]
    candidates += [(a, b) for a in codes for b in known]
    pairs = [pair for pair in (compare(a, b, boilerplate, threshold) for a, b in candidates) if pair]
    return sorted(pairs, key=lambda pair: (-pair.score, pair.first, pair.second))


def markdown(pairs, compared, threshold, known_names=()):
    """similarity.md: the pairs, one row each, with where their passages lie."""
    text = rubric.md_text
    lines = ['# Similar code', '',
             'Evidence for the teacher, not a grade. %d submissions compared%s, each with each, by '
             'copydetect (names, strings and comments replaced, so renaming does not hide a copy); '
             'the code the course gives every student left out. A pair is listed when at least '
             '%d%% of either one\'s code is found in the other. The passages side by side: '
             '[%s](%s).'
             % (compared, ' and with %d known solutions (%s)' % (len(known_names), ', '.join(
                 text(name) for name in known_names)) if known_names else '',
                round(threshold * 100), HTML_FILE, HTML_FILE), '']
    if not pairs:
        lines.append('No pair is that alike.')
        return '\n'.join(lines) + '\n'
    lines += ['| first | second | alike | share of first in second | share of second in first | '
              'language |', '|---|---|---|---|---|---|']
    for pair in pairs:
        lines.append('| %s | %s | %d%% | %d%% | %d%% | %s |'
                     % (text(pair.first), text(pair.second), round(pair.score * 100),
                        round(pair.shares[0] * 100), round(pair.shares[1] * 100), pair.language))
    lines.append('')
    for pair in pairs:
        lines += ['## %s and %s' % (text(pair.first), text(pair.second)), '',
                  '- in %s: %s' % (text(pair.first), text(', '.join(pair.lines[0]))),
                  '- in %s: %s' % (text(pair.second), text(', '.join(pair.lines[1]))), '']
    return '\n'.join(lines)


def html_page(pairs):
    """similarity.html: each pair's code side by side, the passages they share marked."""
    parts = ['<!DOCTYPE html><html><head><meta charset="utf-8"><title>Similar code</title>'
             '<style>body{font-family:sans-serif} table{width:100%;table-layout:fixed;'
             'border-collapse:collapse} td{vertical-align:top;border:1px solid #ccc;padding:4px}'
             'pre{white-space:pre-wrap;font-size:12px} mark{background:#fd5}</style></head><body>',
             '<h1>Similar code</h1><p>Evidence for the teacher, not a grade.</p>']
    if not pairs:
        parts.append('<p>No pair is that alike.</p>')
    for pair in pairs:
        parts.append('<h2>%s and %s: %d%% alike (%s)</h2><table><tr><th>%s</th><th>%s</th></tr>'
                     '<tr><td><pre>%s</pre></td><td><pre>%s</pre></td></tr></table>'
                     % (html.escape(pair.first), html.escape(pair.second), round(pair.score * 100),
                        pair.language, html.escape(pair.first), html.escape(pair.second),
                        pair.passages[0], pair.passages[1]))
    parts.append('</body></html>\n')
    return '\n'.join(parts)


def known_solutions(folder):
    """The solutions in a folder of them: each subfolder that holds a package, or the folder
    itself when it is one solution (its subfolders are packages, as in a src folder)."""
    folders = submission.subfolders(folder)
    if any(os.path.isfile(os.path.join(sub, 'package.xml')) for sub in folders):
        return [folder]
    return [sub for sub in folders if submission.package_dirs(sub)]


def write(report_dir, named_paths, known_paths=(), threshold=THRESHOLD):
    """Compare a class ({name: path}) and known solutions ({name: path}); write similarity.md
    and similarity.html into report_dir; the pairs."""
    codes = [code_of(name, path) for name, path in named_paths.items()]
    known = [code_of(name, path) for name, path in dict(known_paths).items()]
    pairs = similar_pairs(codes, known, threshold)
    rubric.write_whole(os.path.join(report_dir, MARKDOWN_FILE),
                       markdown(pairs, len(codes), threshold, [code.name for code in known]))
    rubric.write_whole(os.path.join(report_dir, HTML_FILE), html_page(pairs))
    return pairs
