"""Saving files from a request: only inside allowed folders, atomically, and losing nothing on failure."""
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

from flatsim.authoring import saving
from flatsim.errors import AuthoringError

SOURCES = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'src')
NOBODY = 65534


@pytest.fixture
def area(tmp_path):
    allowed = tmp_path / 'allowed'
    (allowed / 'worlds').mkdir(parents=True)
    (tmp_path / 'outside').mkdir()
    return tmp_path


def test_a_file_is_written_inside_the_allowed_folder(area):
    path = saving.save_text([str(area / 'allowed')], str(area / 'allowed' / 'worlds'), 'room.world', 'text')
    assert path == str(area / 'allowed' / 'worlds' / 'room.world')
    assert open(path).read() == 'text'
    assert os.listdir(area / 'allowed' / 'worlds') == ['room.world']


@pytest.mark.parametrize('name, message', [
    ('../outside.world', "may not hold '..'"),
    ('sub/../../x.world', "may not hold '..'"),
    ('/etc/passwd', 'must be relative'),
    ('~/x.world', 'must be relative'),
    ('', 'is empty'),
    ('a//b', 'empty parts'),
    ('nul\0.world', 'NUL'),
])
def test_a_bad_name_is_refused(area, name, message):
    with pytest.raises(AuthoringError, match=message):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed'), name, 'text')
    assert sorted(os.listdir(area / 'allowed')) == ['worlds'] and os.listdir(area / 'outside') == []


def test_a_folder_outside_the_allowed_ones_is_refused(area):
    with pytest.raises(AuthoringError, match='is not inside the folders flatsim may write to'):
        saving.save_text([str(area / 'allowed')], str(area / 'outside'), 'x.world', 'text')
    with pytest.raises(AuthoringError, match='is not inside'):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed') + '_twin', 'x.world', 'text')
    with pytest.raises(AuthoringError, match='absolute path'):
        saving.save_text([str(area / 'allowed')], 'allowed/worlds', 'x.world', 'text')
    assert os.listdir(area / 'outside') == []


def test_symlinks_that_lead_out_are_refused(area):
    os.symlink(str(area / 'outside'), str(area / 'allowed' / 'door'))
    os.symlink(str(area / 'outside' / 'x.world'), str(area / 'allowed' / 'worlds' / 'trap.world'))
    with pytest.raises(AuthoringError, match='is not inside'):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed' / 'door'), 'x.world', 'text')
    with pytest.raises(AuthoringError, match='leads outside'):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed'), 'door/x.world', 'text')
    with pytest.raises(AuthoringError, match='leads outside'):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed' / 'worlds'), 'trap.world', 'text')
    assert os.listdir(area / 'outside') == []


def test_a_symlinked_allowed_folder_is_still_allowed(area):
    os.symlink(str(area / 'allowed'), str(area / 'link'))
    path = saving.save_text([str(area / 'link')], str(area / 'allowed' / 'worlds'), 'a.world', 'text')
    assert open(path).read() == 'text'


def test_a_missing_folder_gives_an_error_naming_it(area):
    missing = str(area / 'allowed' / 'nowhere')
    with pytest.raises(AuthoringError, match='the folder %s does not exist' % missing):
        saving.save_text([str(area / 'allowed')], missing, 'x.world', 'text')
    assert not os.path.exists(missing)


def test_a_file_where_a_folder_should_be_fails_for_root_too(area):
    (area / 'allowed' / 'plain').write_text('not a folder')
    with pytest.raises(AuthoringError, match='plain'):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed'), 'plain/x.world', 'text')
    assert (area / 'allowed' / 'plain').read_text() == 'not a folder'


def test_saving_over_a_file_that_fails_leaves_the_old_file(area, monkeypatch):
    old = area / 'allowed' / 'worlds' / 'room.world'
    old.write_text('the old world')
    os.chmod(str(old), 0o640)

    def full_disk(descriptor):
        raise OSError(28, 'No space left on device')

    monkeypatch.setattr(os, 'fsync', full_disk)
    with pytest.raises(AuthoringError, match='No space left on device; the file there is unchanged'):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed' / 'worlds'), 'room.world', 'new')
    assert old.read_text() == 'the old world'
    assert os.listdir(area / 'allowed' / 'worlds') == ['room.world']
    monkeypatch.undo()
    saving.save_text([str(area / 'allowed')], str(area / 'allowed' / 'worlds'), 'room.world', 'new')
    assert old.read_text() == 'new' and oct(os.stat(str(old)).st_mode & 0o777) == oct(0o640)


def test_text_that_cannot_be_written_leaves_the_old_file(area):
    old = area / 'allowed' / 'worlds' / 'room.world'
    old.write_text('the old world')
    with pytest.raises(AuthoringError, match='unchanged'):
        saving.save_text([str(area / 'allowed')], str(area / 'allowed' / 'worlds'), 'room.world', 'bad \udc80')
    assert old.read_text() == 'the old world' and os.listdir(old.parent) == ['room.world']


SAVE_AS_NOBODY = """
import sys
sys.path.insert(0, sys.argv[1])
from flatsim.authoring import saving
from flatsim.errors import AuthoringError
try:
    saving.save_text([sys.argv[2]], sys.argv[2], 'room.world', 'new')
except AuthoringError as error:
    print(error)
    sys.exit(3)
"""


def test_a_read_only_folder_gives_an_error_naming_it_and_keeps_the_old_file():
    """chmod does not stop root, so as root the save runs as nobody (setpriv), for whom it does."""
    parent = tempfile.mkdtemp(prefix='flatsim-readonly-')
    try:
        os.chmod(parent, 0o755)
        folder = os.path.join(parent, 'worlds')
        os.mkdir(folder)
        with open(os.path.join(folder, 'room.world'), 'w') as stream:
            stream.write('the old world')
        os.chmod(os.path.join(folder, 'room.world'), 0o644)
        os.chmod(folder, 0o555)
        command = [sys.executable, '-c', SAVE_AS_NOBODY, os.path.abspath(SOURCES), folder]
        if os.geteuid() == 0:
            if shutil.which('setpriv') is None:
                pytest.skip('running as root without setpriv to drop to an unprivileged user')
            command = ['setpriv', '--reuid=%d' % NOBODY, '--regid=%d' % NOBODY, '--clear-groups'] + command
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
        assert done.returncode == 3, done.stderr
        assert done.stdout.strip() == 'cannot write in the folder %s: Permission denied' % folder
        with open(os.path.join(folder, 'room.world')) as stream:
            assert stream.read() == 'the old world'
        assert os.listdir(folder) == ['room.world']
    finally:
        os.chmod(os.path.join(parent, 'worlds'), 0o755)
        shutil.rmtree(parent)


def test_several_files_are_checked_before_any_is_written(area):
    with pytest.raises(AuthoringError, match="may not hold '..'"):
        saving.replace_folder([str(area / 'allowed')], str(area / 'allowed'), 'm',
                              {'model.config': 'a', '../model.sdf': 'b'})
    assert sorted(os.listdir(area / 'allowed')) == ['worlds']
    written = saving.replace_folder([str(area / 'allowed')], str(area / 'allowed'), 'm',
                                    {'model.config': 'a', 'meshes/model.dae': 'b'})
    assert written == str(area / 'allowed' / 'm')
    assert [open(os.path.join(written, name)).read() for name in ('model.config', 'meshes/model.dae')] \
        == ['a', 'b']
