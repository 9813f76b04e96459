"""The grader against submissions that try to get out of its sandbox, one route each.

The hostile submissions (hostile_variants.HOSTILE) are graded in one run of `grade`
over a folder, two at a time, without chase trials (only what the sandbox
lets through matters here) and with small limits. The routes that need a
grade of their own are in test_grade_hostile_runs.py.

Besides its own route, each test checks that nothing outside the scratch
folder changed: a canary folder holding the paths the fixtures aim at, a
root-only secret and a canary file inside this workspace, this workspace's
own launch and grader files, and the kernel's core_pattern.
"""
import json
import os
import pwd
import re
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402
from grade_support import processes_of_uid  # noqa: E402
from hostile_support import (CLASS_GRADE_TIMEOUT_S, CORE_PATTERN, CORE_UID_BASE,  # noqa: E402
                             ESCAPE_MARKERS, GRADER_MEMORY_BOUND, GRADER_SECRETS, IN_FOLDER,
                             LIMITS, NEEDS_ROOT_AND_BWRAP, REPORT_BOUND, UID_BASE,
                             everything_written, folder_size, host, items, log, notes, sandbox_uid,
                             watched_grade)
from markdown_check import blocks, first_table, headings, outside_fences  # noqa: E402

pytestmark = NEEDS_ROOT_AND_BWRAP


@pytest.fixture(scope='module')
def graded(host, tmp_path_factory):
    """(the grade process, {submission: its JSON}, the report folder)."""
    folder = tmp_path_factory.mktemp('hostile')
    for name in IN_FOLDER:
        variants.compose(name, folder, **host.params)
    out = tmp_path_factory.mktemp('hostile_graded')
    proc, watch = watched_grade([folder, '--class', '--trials', '0', '--jobs', '2',
                                 '--output', out / 'report', '--json', out / 'all.json'] + LIMITS,
                                timeout=CLASS_GRADE_TIMEOUT_S, env=dict(os.environ, **GRADER_SECRETS))
    assert os.path.exists(out / 'all.json'), proc.stdout
    with open(out / 'all.json') as stream:
        results = {entry['name']: entry for entry in json.load(stream)['submissions']}
    return proc, results, str(out / 'report'), watch.peaks, watch.session_uids


def test_links_planted_in_the_scratch_at_build_time_lead_nowhere(graded, host):
    """Its CMakeLists links run/, session.json, result.json and the other names the grader
    writes after the build to the canary folder."""
    name = 'hostile_planted_links'
    evidence = items(graded, name)
    for item in ('builds', 'world_launches', 'sensors', 'drive_bot_service'):
        assert evidence[item]['passed'], (item, evidence[item]['evidence'])
    assert sandbox_uid(graded[1][name]) > UID_BASE
    assert 'writes only its build folder while it builds and its run folder while its nodes run' \
        in graded[1][name]['isolation']
    host.assert_unchanged()


def test_links_in_the_submission_are_neither_copied_nor_followed_and_the_report_names_them(graded, host):
    """A launch file linking to a host file (which the grader would rewrite) and a folder
    linking out of the submission."""
    name = 'hostile_links'
    said = notes(graded, name)
    assert 'my_robot/launch/extra.launch -> %s/host.launch (points outside the submission)' \
        % host.canary in said, said
    assert 'my_robot/outside -> %s (points outside the submission)' % host.canary in said, said
    assert 'shared.launch' not in said                   # a link inside the submission is copied
    evidence = items(graded, name)
    assert evidence['world_launches']['passed'], evidence['world_launches']['evidence']
    with open(os.path.join(graded[2], name, 'report.md')) as stream:
        assert 'my_robot/launch/extra.launch' in stream.read()
    host.assert_unchanged()


def test_root_only_files_cannot_be_read_from_the_build_or_a_node(graded, host):
    name = 'hostile_reads'
    written = everything_written(os.path.join(graded[2], name))
    assert host.secret_text not in written
    assert host.shadow_line not in written
    for log_name in ('build.log', 'ball_chaser_launch.log'):
        text = log(graded, name, log_name)
        assert 'REFUSED read %s: [Errno 13] Permission denied' % host.secret in text, text[-3000:]
        assert 'REFUSED read /etc/shadow: [Errno 2] No such file or directory' in text, text[-3000:]
        assert 'READ ' not in text
    host.assert_unchanged()


def test_writes_outside_the_scratch_are_refused_to_the_build_and_to_a_node(graded, host):
    """The kernel's core_pattern (a host escape for a process running as root), the canary
    folder and a file of this workspace."""
    name = 'hostile_writes'
    for log_name, canary in (('build.log', 'from_build'), ('ball_chaser_launch.log', 'from_node')):
        text = log(graded, name, log_name)
        assert 'WROTE' not in text, text[-3000:]
        for path in (CORE_PATTERN, os.path.join(host.canary, canary), host.project_file):
            assert 'REFUSED write %s' % path in text, (path, text[-3000:])
    host.assert_unchanged()


def test_the_network_reaches_nothing_outside_the_session(graded, host):
    """An outside address, a port on the host's loopback and a Unix socket in this workspace,
    from the build and from a node."""
    name = 'hostile_network'
    assert host.tcp.accepted == 0 and host.unix.accepted == 0
    for log_name in ('build.log', 'ball_chaser_launch.log'):
        text = log(graded, name, log_name)
        assert 'CONNECTED' not in text, text[-3000:]
        for address in ('192.0.2.1:80', '127.0.0.1:%d' % host.params['PORT'], 'unix:' + host.unix_path):
            assert 'REFUSED connect %s' % address in text, (address, text[-3000:])
    host.assert_unchanged()


def test_a_fork_bomb_in_the_build_stops_at_the_process_limit_and_the_item_says_so(graded, host):
    name = 'hostile_fork_bomb'
    evidence = items(graded, name)['builds']['evidence']
    assert 'the build hit the process limit of 200 (' in evidence, evidence
    match = re.search(r'THREADS (\d+), then: can\'t start new thread', log(graded, name, 'build.log'))
    assert match and int(match.group(1)) < 200
    assert items(graded, name)['world_launches']['passed']      # the grader went on
    host.assert_unchanged()


def test_a_memory_bomb_stops_at_the_memory_limit_and_the_report_says_so(graded, host):
    name = 'hostile_memory_bomb'
    said = notes(graded, name)
    assert "the submission's nodes hit the memory limit of 768 MiB (the kernel killed" in said, said
    text = log(graded, name, 'ball_chaser_launch.log')
    assert text.count('ALLOCATED 400 MiB') < 3
    assert re.search(r'^MEMORY [0-2] of 3 allocated$', text, re.M), text[-3000:]
    assert items(graded, name)['world_launches']['passed']
    host.assert_unchanged()


def test_a_node_that_floods_its_output_leaves_a_capped_log(graded, host):
    name = 'hostile_flood'
    path = os.path.join(graded[2], name, 'logs', 'ball_chaser_launch.log')
    assert os.path.getsize(path) < 256 * 1024 + 4096
    text = log(graded, name, 'ball_chaser_launch.log')
    assert re.search(r'\[the grader cut \d+ bytes \(18\.\d MiB\) here: it keeps the first and last '
                     r'128 KiB of each log\]', text), text[-2000:]
    # One note for the log, however often the launch was started afresh into it.
    said = notes(graded, name)
    assert len(re.findall(r'logs/ball_chaser_launch.log: [\d.]+ MiB cut of', said)) == 1, said
    assert re.search(r'logs/ball_chaser_launch.log: (18\.\d MiB cut of 19\.\d MiB written \(the first '
                     r'and last 128 KiB kept\)|\d+\.\d MiB cut of \d+\.\d MiB written \(\d starts of '
                     r'the launch, 256 KiB kept in all\))', said), said
    host.assert_unchanged()


def mounted_on_the_machine(text):
    """The lines of the machine's mount table that hold text."""
    with open('/proc/1/mountinfo') as stream:
        return [line for line in stream if text in line]


def test_a_build_that_fills_its_disk_stops_at_the_disk_limit_and_the_item_says_so(graded, host):
    """It writes 128 MiB in its TMPDIR at configure time, past the limit of 64M."""
    name = 'hostile_fills_disk_building'
    evidence = items(graded, name)['builds']
    assert not evidence['passed']
    assert 'the build hit the disk limit of 64 MiB (its folders are full: ' in evidence['evidence'], \
        evidence['evidence']
    match = re.search(r'FILLED (\d+) MiB, 0 files, then: \[Errno 28\] No space left on device',
                      log(graded, name, 'build.log'))
    assert match and int(match.group(1)) < 64, log(graded, name, 'build.log')[-3000:]
    assert '64 MiB of disk for its folders together (a filesystem of their own, an ext4 image ' \
        'in the scratch folder)' in graded[1][name]['isolation']
    # The grader went on: every item has its verdict, in a report of its own.
    assert [item['name'] for item in graded[1][name]['items']][-1] == 'chase'
    assert os.path.exists(os.path.join(graded[2], name, 'report.md'))
    assert mounted_on_the_machine('grade_%s' % name) == []
    host.assert_unchanged()


def test_a_node_that_fills_its_disk_with_files_stops_at_the_disk_limit_and_the_report_says_so(graded,
                                                                                          host):
    """It makes up to 100000 empty files: past the inodes of a 64M filesystem."""
    name = 'hostile_fills_disk_running'
    said = notes(graded, name)
    assert "the submission's nodes hit the disk limit of 64 MiB (its folders are full: " in said, said
    match = re.search(r'FILLED 0 MiB, (\d+) files, then: \[Errno 28\] No space left on device',
                      log(graded, name, 'ball_chaser_launch.log'))
    assert match and int(match.group(1)) < 100000, log(graded, name, 'ball_chaser_launch.log')[-3000:]
    assert items(graded, name)['builds']['passed'] and items(graded, name)['world_launches']['passed']
    assert mounted_on_the_machine('grade_%s' % name) == []
    host.assert_unchanged()


def test_a_submission_larger_than_its_disk_is_a_failed_build_that_says_so(graded, host):
    name = 'hostile_huge_file'
    evidence = items(graded, name)['builds']
    assert not evidence['passed']
    assert evidence['evidence'].startswith(
        "not built: the submission could not be copied into the grader's workspace: No space "
        "left on device; the copy of the submission hit the disk limit of 64 MiB (its folders are "
        "full: "), evidence['evidence']
    assert mounted_on_the_machine('grade_%s' % name) == []
    host.assert_unchanged()


def test_the_grader_reads_the_world_the_simulator_names_only_as_the_submission_could(graded, host):
    """world.launch gives the simulator a root-only world file, and a node names it as the
    simulator's: the grader reads the world through a copy the submission's sandbox makes,
    which cannot open it, and never the parameter."""
    name = 'hostile_world_param'
    assert 'SET /flatsim/world_name' in log(graded, name, 'world_launch.log')
    evidence = items(graded, name)['world_launches']['evidence']
    assert 'r 0.43 m' not in everything_written(os.path.join(graded[2], name)), evidence
    assert 'of the world file %s and the models it includes, not read: %s: Permission denied' % (
        host.secret_world, host.secret_world) in evidence, evidence
    host.assert_unchanged()


@pytest.mark.parametrize('name', ['hostile_preload_hook', 'hostile_library_in_devel',
                                  'hostile_shadowing_programs'])
def test_the_built_workspaces_environment_never_reaches_a_program_the_grader_runs_as_root(graded, host,
                                                                                         name):
    """An env hook that sets LD_PRELOAD, a library of bwrap's (libcap.so.2) in devel/lib, and
    prlimit, setpriv and env in devel/bin: the setup files put each where a program that starts
    the sandbox as root would load or run it, and each, run as root, tries to leave a marker
    outside the sandbox (ESCAPED in the log) and to read the root-only secret."""
    evidence = items(graded, name)
    assert evidence['builds']['passed'], evidence['builds']['evidence']
    assert evidence['world_launches']['passed'], evidence['world_launches']['evidence']
    written = everything_written(os.path.join(graded[2], name))
    assert 'ESCAPED' not in written, [line for line in written.splitlines() if 'ESCAPED' in line]
    assert host.secret_text not in written
    for marker in ESCAPE_MARKERS:
        assert not os.path.exists(os.path.join(host.canary, marker))
    host.assert_unchanged()


def test_only_the_allowed_variables_of_the_graders_environment_reach_the_sandbox(graded, host):
    """The grade runs with the teacher's secrets in its environment; the build and a node print
    theirs."""
    name = 'hostile_environment'
    written = everything_written(os.path.join(graded[2], name))
    for variable, value in GRADER_SECRETS.items():
        assert value not in written, variable
        assert 'ENV %s=' % variable not in written, variable
    for log_name in ('build.log', 'ball_chaser_launch.log'):
        text = log(graded, name, log_name)
        assert 'ENV ROS_PACKAGE_PATH=' in text and 'ENV LD_PRELOAD=' not in text, text[-3000:]
        home = re.search(r'^ENV HOME=(.*)$', text, re.M).group(1)
        assert home.endswith('/home') and home != os.environ.get('HOME'), home
    assert re.search(r'^ENV ROS_MASTER_URI=http://localhost:\d+$', log(graded, name, 'ball_chaser_launch.log'),
                     re.M)
    host.assert_unchanged()


def test_the_grader_does_not_read_the_source_folder_again_once_the_build_has_run(graded, host):
    """At the end of its configure step, the CMakeLists puts a link to a root-only folder in
    place of src; that folder's package.xml names a package whose message target make lists."""
    name = 'hostile_swapped_src'
    assert 'SWAPPED src' in log(graded, name, 'build.log')
    evidence = items(graded, name)['builds']
    assert not evidence['passed']
    assert 'message targets built first: ball_chaser_generate_messages' in evidence['evidence'], \
        evidence['evidence']
    assert 'the build put links in place of' in evidence['evidence'], evidence['evidence']
    assert host.root_only_package not in everything_written(os.path.join(graded[2], name))
    host.assert_unchanged()


def test_a_package_named_like_one_of_the_graders_is_refused_and_the_report_says_why(graded, host):
    """Its robot package depends on a gazebo_ros of its own, which would take the place of the
    simulator's stand-in."""
    name = 'hostile_named_like_ours'
    evidence = items(graded, name)['builds']
    assert not evidence['passed']
    assert evidence['evidence'] == (
        "not built: the submission's package gazebo_ros (gazebo_ros) has the name of a package of "
        "the grader's own (the simulator, its stand-ins for Gazebo's packages and the grader), which "
        "it would take the place of; rename it or leave it out of the submission"), evidence['evidence']
    assert [item['evidence'] for item in graded[1][name]['items'][1:]] == ['not run: the build failed'] * 6
    with open(os.path.join(graded[2], name, 'report.md')) as stream:
        assert 'gazebo_ros (gazebo_ros) has the name of a package of the grader' in stream.read()
    host.assert_unchanged()


def test_a_package_whose_name_climbs_out_of_the_workspace_is_refused_and_nothing_is_copied(graded, host):
    """The robot package's <name> is ../../(...)/CANARY/cron.d: root's copy of the package would
    land there, a folder root's cron reads."""
    name = 'hostile_package_name'
    evidence = items(graded, name)['builds']
    assert not evidence['passed']
    assert 'the package is refused: its <name>' in evidence['evidence'], evidence['evidence']
    assert 'is not a ROS package name (REP 144' in evidence['evidence'], evidence['evidence']
    assert not os.path.lexists(os.path.join(host.canary, 'cron.d'))
    host.assert_unchanged()


def test_a_dependency_whose_name_climbs_out_of_the_workspace_is_refused_and_nothing_is_copied(graded,
                                                                                              host):
    """ball_chaser depends on a package of the submission named ../../(...)/CANARY/ssh, which
    holds an authorized_keys."""
    name = 'hostile_dependency_name'
    said = notes(graded, name)
    assert 'the package is refused: its <name>' in said, said
    assert items(graded, name)['builds']['passed'], items(graded, name)['builds']['evidence']
    assert not os.path.lexists(os.path.join(host.canary, 'ssh'))
    host.assert_unchanged()


def test_processes_a_node_leaves_behind_are_said_and_killed(graded, host):
    name = 'hostile_detach'
    said = notes(graded, name)
    assert 'ball_chaser.launch left 1 process running outside roslaunch (' in said, said
    assert processes_of_uid(sandbox_uid(graded[1][name])) == []
    host.assert_unchanged()


def test_a_chaser_launch_that_ends_by_itself_is_said(graded, host):
    name = 'hostile_quits'
    said = notes(graded, name)
    assert 'ball_chaser.launch had ended by itself before the grader stopped it' in said, said
    host.assert_unchanged()


def test_a_service_that_drips_its_header_fails_its_item_and_the_grade_goes_on(graded, host):
    """drive_bot's node serves the course's service from a socket that answers one byte every
    4 s: the grader's probe of its header ends at its deadline (the class grade, bounded by
    GRADE_TIMEOUT_S, would otherwise never end), and the item says what the service did."""
    name = 'hostile_drips_service'
    assert 'DRIPPING /ball_chaser/command_robot' in log(graded, name, 'ball_chaser_launch.log')
    evidence = items(graded, name)['drive_bot_service']
    assert not evidence['passed']
    assert evidence['evidence'].startswith(
        'the service does not answer: no whole answer within 5 s while reading the length of its '
        'header (2 of its 4 bytes came)'), evidence['evidence']
    # The grade went on past it.
    assert items(graded, name)['stops_without_ball']['evidence'] != 'not run: an earlier step failed'
    assert processes_of_uid(sandbox_uid(graded[1][name])) == []
    host.assert_unchanged()


def test_names_and_log_lines_that_hold_markdown_cannot_forge_the_report(graded, host):
    """A link left out whose name holds a passing chase row and a "# Grade: PASS" heading; a node
    that logs a code fence and the same; a node registered at the master under such a name."""
    name = 'hostile_markdown'
    assert 'FORGING' in log(graded, name, 'ball_chaser_launch.log')
    with open(os.path.join(graded[2], name, 'report.md')) as stream:
        report = stream.read()
    assert headings(report, 1) == ['# Go Chase It: %s' % name]
    assert [line for kind, line in blocks(report) if kind.startswith('heading') and 'Grade' in line] == []
    table = first_table(report)
    assert [row.split('|')[1].strip() for row in table[2:]] == [
        '`%s`' % item['name'] for item in graded[1][name]['items']]
    # Where the forged text shows, it is text: escaped, or inside a fence.
    assert outside_fences(report, 'forged')
    for _kind, line in outside_fences(report, 'forged'):
        assert '| `chase`' not in line, line
    # The node's log lines are quoted whole, inside the fence.
    assert any(line.endswith('[FATAL] ```') for kind, line in blocks(report) if kind == 'fenced'), report
    with open(os.path.join(graded[2], 'summary.md')) as stream:
        summary = stream.read()
    assert headings(summary, 1) == ['# Go Chase It: %d submissions' % len(IN_FOLDER)]
    assert len(first_table(summary)) == 2 + len(IN_FOLDER)
    host.assert_unchanged()


def test_a_node_that_fills_dev_shm_stops_at_its_size_and_the_report_says_it(graded, host):
    name = 'hostile_fills_shm'
    match = re.search(r'^SHM (\d+) MiB, then: dd: error writing \'/dev/shm/fill\': No space left on '
                      r'device', log(graded, name, 'ball_chaser_launch.log'), re.M)
    assert match and int(match.group(1)) <= 64, log(graded, name, 'ball_chaser_launch.log')[-2000:]
    assert 'a /dev/shm of 64 MiB in each sandbox' in graded[1][name]['isolation']
    assert items(graded, name)['world_launches']['passed']
    host.assert_unchanged()


def test_the_build_and_the_nodes_cannot_make_user_namespaces(graded, host):
    """unshare -U from the build and from a node: where the machine lets a uid make a user
    namespace, the sandbox closes it (bubblewrap's --disable-userns)."""
    name = 'hostile_userns'
    for log_name in ('build.log', 'ball_chaser_launch.log'):
        text = log(graded, name, log_name)
        assert 'USERNS REFUSED: unshare: unshare failed' in text, text[-2000:]
        assert 'USERNS MADE' not in text
    assert "it cannot make user namespaces (bubblewrap's --disable-userns)" in graded[1][name]['isolation']
    assert items(graded, name)['world_launches']['passed']
    host.assert_unchanged()


def assert_bounded(graded, name):
    """The submission's report folder and the grader's memory stayed within their bounds."""
    assert folder_size(os.path.join(graded[2], name)) < REPORT_BOUND
    assert 0 < graded[3][name] < GRADER_MEMORY_BOUND, graded[3]


def test_the_graders_node_runs_as_a_uid_of_its_own_not_as_root(graded):
    """The session, whose node /grade_probe every node of the submission reaches (XML-RPC,
    TCPROS, the stand-in service), ran as a uid of its own: not root, not the submission's,
    and no account's."""
    seen = graded[4]
    assert len(seen) >= len(IN_FOLDER) // 2, (sorted(seen), IN_FOLDER)
    for name, uids in seen.items():
        assert 0 not in uids, (name, uids)
        result = graded[1][name]
        assert sandbox_uid(result) not in uids
        for uid in uids:
            assert uid > CORE_UID_BASE
            with pytest.raises(KeyError):
                pwd.getpwuid(uid)


def test_a_rosout_flood_fills_no_log_past_its_cap_and_the_report_names_it(graded, host):
    """A node sends 300 MiB and more of /rosout messages, 1 MiB each: rosout writes at most roscore's
    file size into its own folder, and the report keeps 256 KiB of it."""
    name = 'hostile_rosout_flood'
    assert 'ROSOUT 300 sent' in log(graded, name, 'world_launch.log')
    said = notes(graded, name)
    match = re.search(r'(logs/ros/log/[\w-]+/rosout\.log): [\d.]+ MiB cut of [\d.]+ MiB written \(the '
                      r'first and last 128 KiB kept\)', said)
    assert match, said
    assert os.path.getsize(os.path.join(graded[2], name, match.group(1))) < 256 * 1024 + 4096
    assert_bounded(graded, name)
    host.assert_unchanged()


def test_log_calls_to_roscore_fill_no_log_past_its_cap_and_the_report_names_them(graded, host):
    """A node calls log() on roscore's roslaunch server with 100 MiB, 1 MiB a call."""
    name = 'hostile_log_flood'
    assert re.search(r'^LOGGED \d{3}$', log(graded, name, 'world_launch.log'), re.M)
    said = notes(graded, name)
    assert re.search(r'logs/roscore\.log: 9\d\.\d MiB cut of (9\d\.\d|100) MiB written \(the first '
                     r'and last 128 KiB kept\)', said), said
    assert os.path.getsize(os.path.join(graded[2], name, 'logs', 'roscore.log')) < 256 * 1024 + 4096
    assert_bounded(graded, name)
    host.assert_unchanged()


def test_parameters_past_the_masters_bounds_are_refused_and_the_report_says_so(graded, host):
    """A node sets parameters of 8 MiB on the master, 192 MiB in all, then one of 64 MiB: the
    master holds 64 MiB of parameters at most and takes no call larger than 16 MiB, so it
    refuses the rest, lives on, and the report names the node."""
    name = 'hostile_param_bomb'
    said_by_node = log(graded, name, 'world_launch.log')
    assert 'PARAM 0 SET' in said_by_node
    assert re.search(r'^PARAM 23 REFUSED: .*parameters would hold more than 67108864 bytes', said_by_node,
                     re.M), said_by_node[-3000:]
    # The master answers 413 and closes before the call has been sent: the node hears a broken pipe.
    assert re.search(r'^PARAM huge REFUSED: ', said_by_node, re.M), said_by_node[-3000:]
    said = notes(graded, name)
    assert re.search(r'the ROS master refused \d+ parameters from /hostile \(the last: /hostile_bomb_23, '
                     r'\d+ bytes\): it holds at most 64 MiB of parameters', said), said
    assert re.search(r'the ROS master refused \d+ calls? from 127\.0\.0\.1 \(the last: \d+ bytes\): it '
                     r'takes no call larger than 16 MiB', said), said
    assert 'the kernel killed' not in said
    assert items(graded, name)['drive_bot_service']['passed']
    assert_bounded(graded, name)
    host.assert_unchanged()


def test_a_message_larger_than_any_camera_frame_is_refused_before_it_is_read(graded, host):
    """A node announces a 1.5 GB message to the grader's /cmd_vel subscriber and sends 1.4 GiB
    of it: the grader closes the connection at the length."""
    name = 'hostile_message_bomb'
    assert 'ANNOUNCED 1500000000' in log(graded, name, 'world_launch.log')
    said = notes(graded, name)
    assert re.search(r'the grader refused a message of 1\.4 GiB on /cmd_vel from /hostile \(127\.0\.0'
                     r'\.1:\d+\) \(1 time\), larger than the 8 MiB it takes', said), said
    assert items(graded, name)['drive_bot_service']['passed']
    assert_bounded(graded, name)
    host.assert_unchanged()
