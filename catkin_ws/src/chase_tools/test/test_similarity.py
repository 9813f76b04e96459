"""Copied work across a class: near-copies are found, originals and the course's templates are not."""
import os
import shutil
import subprocess
import sys

import pytest

from chase_tools.grading import rubric, similarity

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402

ORIGINAL = os.path.join(variants.EXTRA, 'original_chaser')
TEMPLATES = os.path.join(HERE, '..', 'course', 'templates')
# What a student who copies does to hide it: other names, other comments, other messages.
DISGUISE = [('DriveBot', 'Driver'), ('self.publisher', 'self.vel_pub'), ('handle', 'on_call'),
            ('command', 'twist_msg'), ('steer', 'direction'), ('pixels', 'px'), ('columns', 'cols'),
            ('Ready to send wheel commands', 'driver is up'), ('offset', 'shift'),
            ('callback', 'on_image'), ('\n\n\n', '\n\n# written by me\n\n')]


def disguise(folder):
    scripts = os.path.join(folder, 'ball_chaser', 'scripts')
    for name in os.listdir(scripts):
        path = os.path.join(scripts, name)
        with open(path) as stream:
            text = stream.read()
        for old, new in DISGUISE:
            text = text.replace(old, new)
        with open(path, 'w') as stream:
            stream.write(text)


def a_class(folder, chaser_only=False):
    """alice, bob (alice's code disguised) and carol (her own code), in folder."""
    os.makedirs(folder)
    for name in ('alice', 'bob', 'carol'):
        variants.compose('py_correct', folder)
        os.rename(os.path.join(folder, 'py_correct'), os.path.join(folder, name))
        if chaser_only:
            shutil.rmtree(os.path.join(folder, name, 'my_robot'))
    disguise(os.path.join(folder, 'bob'))
    shutil.copytree(ORIGINAL, os.path.join(folder, 'carol'), dirs_exist_ok=True)
    return {name: os.path.join(folder, name) for name in ('alice', 'bob', 'carol')}


def test_a_disguised_copy_is_paired_with_its_original_and_an_original_with_nobody(tmp_path):
    pairs = similarity.write(str(tmp_path), a_class(str(tmp_path / 'class')))
    assert [(pair.first, pair.second) for pair in pairs] == [('alice', 'bob')]
    assert pairs[0].score > 0.9 and pairs[0].language == 'python'
    assert pairs[0].lines[0] == ['ball_chaser/scripts/drive_bot.py:1-24',
                                 'ball_chaser/scripts/process_image.py:1-34']
    with open(tmp_path / similarity.MARKDOWN_FILE) as stream:
        page = stream.read()
    assert '| alice | bob | ' in page and 'carol |' not in page
    assert '3 submissions compared' in page


def test_an_original_shares_only_what_any_two_chasers_share(tmp_path):
    paths = a_class(str(tmp_path / 'class'))
    codes = [similarity.code_of(name, path) for name, path in paths.items()]
    pairs = similarity.similar_pairs(codes, threshold=0.0)
    scores = {(pair.first, pair.second): pair.score for pair in pairs}
    assert scores[('alice', 'bob')] > 0.9
    assert scores[('alice', 'carol')] < 0.4 and scores[('bob', 'carol')] < 0.4


def test_the_code_the_course_gives_every_student_is_left_out(tmp_path):
    """Two students who each filled in the course's process_image.cpp template alike only where
    the template is: their shared code is the course's, not each other's."""
    for name, body in (('dana', '    ROS_INFO("dana");\n'), ('eli', '    for (int i = 0; i < 3; i++) {}\n')):
        scripts = tmp_path / name / 'ball_chaser' / 'src'
        scripts.mkdir(parents=True)
        (tmp_path / name / 'ball_chaser' / 'package.xml').write_text(
            '<package format="2"><name>ball_chaser</name></package>')
        for template in ('drive_bot.cpp', 'process_image.cpp'):
            text = (open(os.path.join(TEMPLATES, template)).read()
                    .replace('    int white_pixel = 255;\n', '    int white_pixel = 255;\n' + body))
            (scripts / template).write_text(text)
    codes = [similarity.code_of(name, str(tmp_path / name)) for name in ('dana', 'eli')]
    with_templates = similarity.similar_pairs(codes, threshold=0.0)
    without_templates = similarity.similar_pairs(
        [similarity.code_of(name, str(tmp_path / name)) for name in ('dana', 'eli')],
        threshold=0.0, boilerplate={})
    assert without_templates and without_templates[0].score > 0.9
    assert with_templates == [] or with_templates[0].score < 0.2


def test_the_side_by_side_page_shows_the_submissions_code_as_text(tmp_path):
    paths = a_class(str(tmp_path / 'class'))
    for name in ('alice', 'bob'):
        with open(os.path.join(paths[name], 'ball_chaser', 'scripts', 'drive_bot.py'), 'a') as stream:
            stream.write('# </pre><script>alert(1)</script>\n')
    similarity.write(str(tmp_path), paths)
    with open(tmp_path / similarity.HTML_FILE) as stream:
        page = stream.read()
    assert '<script>' not in page and '&lt;script&gt;' in page
    assert page.count('<mark>') >= 2 and '<h2>alice and bob: ' in page


def test_a_submissions_name_cannot_write_markdown_of_its_own():
    page = similarity.markdown([similarity.Pair('a|b\n# Grade: PASS', 'c', 1.0, (1.0, 1.0), 'python',
                                                ('', ''), (['x.py:1-2'], ['y.py:1-2']))], 2, 0.6)
    assert '\n# Grade' not in page and '| a\\|b' in page


@pytest.mark.skipif(shutil.which('bwrap') is None, reason='the grader needs bubblewrap')
def test_a_class_grade_lists_its_similar_pairs_and_those_like_a_known_solution(tmp_path):
    """Through `grade --class`: the summary links similarity.md, which names the pair of
    near-copies, and carol against the known solution she was given."""
    a_class(str(tmp_path / 'class'), chaser_only=True)
    known = tmp_path / 'known'
    known.mkdir()
    shutil.copytree(ORIGINAL, known / 'solution_2024')
    shutil.copy(os.path.join(variants.BASE, 'ball_chaser_py', 'package.xml'),
                known / 'solution_2024' / 'ball_chaser')
    out = tmp_path / 'report'
    proc = subprocess.run(['grade', str(tmp_path / 'class'), '--class', '--trials', '0', '--output', str(out),
                           '--similar-to', str(known)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600, check=False)
    assert 'grade: 2 pairs of submissions with unusually similar code' in proc.stdout, proc.stdout
    with open(out / 'summary.md') as stream:
        assert '[similarity.md](similarity.md)' in stream.read()
    with open(out / 'similarity.md') as stream:
        page = stream.read()
    known_name = rubric.md_text('known:solution_2024')
    assert '| alice | bob | ' in page and '| carol | %s | 100%% |' % known_name in page, page
    assert 'and with 1 known solutions (%s)' % known_name in page
