"""The submission's launches and the grader's own simulator: each started in the sandbox,
its launch files prepared for a headless run, and stopped with its logs closed.
"""
import os
import signal
import shutil
import subprocess
import sys
import time

from chase_tools import chase_graph
from chase_tools.grading import evidence, headless_launch, launchread, simulator, worldcopy
from chase_tools.grading.bounds import (LAUNCH_READ_S, LOCKSTEP_MAX_WAIT_S, POLL_S, SIMULATOR_REFUSALS, STOP_GRACE_S,
                                        WORLD_COPY_LOG, WORLD_COPY_S)
from chase_tools.grading.limits import size_text
from chase_tools.grading.logcap import CappedLog, run_captured
from chase_tools.grading.sandbox import Sandbox, environment_paths, flatsim_cache_stand_ins
from chase_tools.grading.sandbox_processes import process_name, sandbox_children
from chase_tools.grading.scratch import hand_over, read_beneath
from chase_tools.procs import ProcessGroup, wait_until


def launch_excerpt(path, out_dir):
    """The decisive lines of a launch log, for an item's evidence, each with its place in the
    report folder (logs/...)."""
    return evidence.log_lines(path, os.path.relpath(path, out_dir))


def _log_from(path, start):
    """The text of a launch's log from byte start on; '' if it cannot be read."""
    try:
        with open(path, errors='replace') as stream:
            stream.seek(start)
            return stream.read()
    except OSError:
        return ''


def launch_processes(path, start=0):
    """(started, died): the process names roslaunch reports in its log, from byte start on."""
    import re
    text = _log_from(path, start)
    return (set(re.findall(r'process\[([\w.-]+)\]: started', text)),
            set(re.findall(r'\[([\w.-]+)\] process has died', text)))


def required_deaths(path, start=0):
    """The required nodes whose death roslaunch reports in its log, from byte start on: it
    then stops the rest of the launch by itself, which can take seconds."""
    import re
    return re.findall(r'REQUIRED process \[([\w.-]+)\] has died!', _log_from(path, start))


class WorldLaunch(ProcessGroup):
    """The launch of the submission's world; alive while the launch and the grader's simulator
    (simulator, a ProcessGroup, set once it runs: bring_up_simulator) both are."""
    SIMULATOR = 'flatsim'

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.simulator = None
        self.simulator_died = False

    def alive(self):
        if not super().alive():
            return False
        # A simulator stopped (its group emptied) is over too.
        self.simulator_died = self.simulator is not None and not (self.simulator.procs
                                                                  and self.simulator.alive())
        return not self.simulator_died


class Launches:
    """Starting and stopping the submission's launches and the grader's simulator; a part of a
    world's run (node.GraderNode holds the state it uses)."""

    def make_sandbox(self):
        """The run's sandbox: the built workspace read-only, the run folder writable."""
        stand_ins = flatsim_cache_stand_ins(self.spec.caches_dir)
        if self.confinement.switch_user:
            hand_over(self.spec.caches_dir, self.confinement.uid, self.confinement.gid)
        return Sandbox(self.spec.run_scratch,
                       visible=environment_paths(self.env) + [self.spec.overlay_root],
                       stand_ins=stand_ins, confinement=self.confinement)

    def start_submission_launch(self, group, package, launch_file, log_path, args=()):
        cmd = ['roslaunch', package, launch_file] + list(args)
        env = dict(self.student_env)
        if self.spec.isolate:
            cmd, env = self.sandbox.wrap(cmd, env)
        group.env = env
        log = CappedLog(log_path, self.log_limit)
        try:
            group.start(cmd, log)
        finally:
            log.started()
        self.open_logs.setdefault(id(group), []).append(log)

    def prepare_launch_files(self, package_dir, remap=False, keep=()):
        """The package's launch files prepared for a headless run (headless_launch.prepare_launch_files),
        shown in place of the originals to every launch from now on; a later preparation of the
        package replaces this one."""
        self.prepared += 1
        copies = os.path.join(self.spec.grader_dir or self.logs, 'launch', str(self.prepared))
        os.makedirs(copies, mode=0o755)
        top = package_dir.rstrip('/') + '/'
        if self.sandbox is None:
            # No sandbox to show the copies in place: they replace the files (never what a link
            # there points at), the originals kept to start from next time.
            for path, original in self.originals.items():
                if path.startswith(top):
                    shutil.copyfile(original, path + '.grading')
                    os.replace(path + '.grading', path)
        changes = headless_launch.prepare_launch_files(package_dir, copies, remap, keep)
        if self.sandbox is not None:
            self.sandbox.overlays = {path: copy for path, copy in self.sandbox.overlays.items()
                                     if not path.startswith(top)}
            self.sandbox.overlays.update(changes.copies)
            return changes
        for path, copy in changes.copies.items():
            if path not in self.originals:
                self.originals[path] = copy + '.original'
                shutil.copyfile(path, self.originals[path])
            shutil.copyfile(copy, path + '.grading')
            os.replace(path + '.grading', path)
        return changes

    def copy_world(self, path, notes):
        """The grader's own copy of the world file the simulator names and of the models it
        includes, made by the submission's sandbox and read as data (worldcopy.py); '' and a
        note when there is none."""
        self.found.model_paths = []
        if not path:
            return ''
        self.world_copies += 1
        # Each world's copies apart: the run folder is every world's.
        relative = os.path.join('world' if self.spec_world_number() == 1
                                else 'world_%d' % self.spec_world_number(), str(self.world_copies))
        cmd, env = [sys.executable, '-m', 'chase_tools.grading.worldcopy', path,
                    os.path.join(self.spec.run_scratch, relative)], dict(self.student_env)
        if self.sandbox is not None:
            cmd, env = self.sandbox.wrap(cmd, env)
        said = run_captured(cmd, env=env, timeout=WORLD_COPY_S, keep=WORLD_COPY_LOG).stdout.strip()
        taken = worldcopy.snapshot(self.spec.run_scratch, relative,
                                   os.path.join(self.spec.grader_dir or self.logs, relative), path)
        if said or taken.left_out:
            notes.append('of the world file %s and the models it includes, not read: %s'
                         % (path, '; '.join(said.splitlines()[:5] + taken.left_out[:5])))
        self.found.model_paths = taken.model_paths
        return taken.world_file

    # -- the grader's simulator -----------------------------------------------------------
    def bring_up_simulator(self, package, launch_file):
        """Start the grader's own simulator as the submission's launch would have started it
        (simulator.py): its world and parameters read by the sandbox (launchread.py), the world
        copied (copy_world). The guard is pinned to it before any node of the submission runs.
        Sets world_file, model_paths and world_notes."""
        notes = self.found.world_notes = []
        asked = self.read_launch(package, launch_file, notes)
        self.guard.claims = ['%s starts the node %s (%s/%s) under the simulator\'s name'
                             % (launch_file, claim['node'], claim['package'], claim['type'])
                             for claim in asked['claims']]
        simulators = asked['simulators']
        if not simulators:
            notes.append('%s starts no simulator (gazebo_ros\'s empty_world.launch, gzserver or '
                         'gazebo): the grader\'s simulator runs an empty world' % launch_file)
        elif len(simulators) > 1:
            notes.append('%s starts %d simulators (%s); the grader\'s simulator runs the first\'s '
                         'world' % (launch_file, len(simulators),
                                    ', '.join(entry['node'] for entry in simulators)))
        chosen = simulators[0] if simulators else {'params': {}, 'args': []}
        self.found.world_file = self.copy_world(launchread.world_of(chosen), notes)
        if self.found.world_file:
            simulator.make_readable(os.path.dirname(self.found.world_file))
        self.start_simulator(chosen['params'], asked['use_sim_time'])
        if not self.spec.extra_world:
            who = ('as uid %d in a sandbox of its own' % self.simulator_sandbox.confinement.uid
                   if self.simulator_sandbox is not None else 'without a sandbox (--no-isolation)')
            self.grade.notes.append('the grader ran the simulator itself (flatsim, see %s), %s, '
                                    'with the world %s gives it: %s' % (
                                        self.log_label(os.path.join(self.logs, 'simulator.log')), who,
                                        launch_file, os.path.basename(self.found.world_file) or 'none'))

    def read_launch(self, package, launch_file, notes):
        """What the launch asks of the simulator (launchread.parse), read in the sandbox; no
        simulator, and a note, if it could not be read."""
        self.launch_reads += 1
        # The run folder is every world's.
        relative = 'launch_read_%d_%d.json' % (self.spec_world_number(), self.launch_reads)
        cmd = [sys.executable, '-m', 'chase_tools.grading.launchread', package, launch_file,
               os.path.join(self.spec.run_scratch, relative)]
        env = dict(self.student_env)
        if self.sandbox is not None:
            cmd, env = self.sandbox.wrap(cmd, env)
        said = run_captured(cmd, env=env, timeout=LAUNCH_READ_S, keep=WORLD_COPY_LOG).stdout.strip()
        try:
            return launchread.parse(read_beneath(self.spec.run_scratch, relative,
                                                 launchread.READ_LIMIT))
        except (OSError, launchread.LaunchReadError) as error:
            notes.append('%s could not be read for its simulator: %s' % (
                launch_file, '; '.join(said.splitlines()[-3:]) or error))
            return {'simulators': [], 'claims': [], 'use_sim_time': None}

    def start_simulator(self, params, use_sim_time):
        """Start flatsim with params as its private parameters, the grader's copy of the world,
        and no studio; once it serves Gazebo's API, pin the guard to it."""
        import roslib.packages
        name = '/' + simulator.NODE_NAME
        for key, value in sorted(params.items()):
            self.master.setParam('%s/%s' % (name, key), value)
        self.master.setParam(name + '/world_name', self.found.world_file or '')
        self.master.setParam(name + '/studio', False)
        self.master.setParam(name + '/lockstep_max_wait', LOCKSTEP_MAX_WAIT_S)
        self.master.setParam('/use_sim_time', use_sim_time if isinstance(use_sim_time, bool) else True)
        program = roslib.packages.find_node('flatsim', 'simulator')[0]
        cmd = [program, '__name:=' + simulator.NODE_NAME]
        env = dict(self.env, GAZEBO_MODEL_PATH=os.pathsep.join(self.found.model_paths))
        if self.sandbox is not None:
            box = self.simulator_sandbox_for()
            # The simulator takes no message larger than the grader's node does.
            cmd = [sys.executable, '-m', 'chase_tools.grading.message_limit',
                   os.path.join(box.scratch, SIMULATOR_REFUSALS)] + cmd
            cmd, env = box.wrap(cmd, env)
            self.sandbox.overlays.update(simulator.standby_overlays(
                os.path.join(self.spec.grader_dir or self.logs, 'standby')))
        self.simulator.env = env
        log = CappedLog(os.path.join(self.logs, 'simulator.log'), self.log_limit)
        try:
            self.simulator.start(cmd, log)
        finally:
            log.started()
        self.open_logs.setdefault(id(self.simulator), []).append(log)
        self.world.simulator = self.simulator
        # Gazebo's API, then ~set_lockstep: the last service flatsim registers.
        wait_until(lambda: chase_graph.LOCKSTEP_SERVICE in self.guard.served_as_simulator(),
                   [self.simulator], self.spec.world_timeout, poll_s=POLL_S)
        self.guard.pin()

    def simulator_sandbox_for(self):
        """The simulator's sandbox (simulator.py): its own folder writable, the workspace and the
        world's copy read-only, numba's caches writable copies."""
        if self.simulator_sandbox is None:
            folder = os.path.join(self.spec.grader_dir or self.logs, 'simulator')
            os.makedirs(folder, mode=0o700)
            confinement = simulator.confinement(folder, self.confinement, self.given_uid('simulator'))
            scratch = os.path.join(folder, 'run')
            caches = os.path.join(folder, 'caches')
            os.makedirs(caches, mode=0o700)
            stand_ins = flatsim_cache_stand_ins(caches)
            visible = environment_paths(self.env)
            if self.found.world_file:
                visible.append(os.path.dirname(self.found.world_file))
            visible += [path for path in self.found.model_paths if path not in visible]
            self.simulator_sandbox = Sandbox(scratch, visible=visible, stand_ins=stand_ins,
                                             confinement=confinement)
            self.simulator_sandbox.prepare()
            if confinement.switch_user:
                hand_over(caches, confinement.uid, confinement.gid)
        return self.simulator_sandbox

    def stop_simulator(self):
        """Stop the grader's simulator, last; a note if it had ended before (its log says why)."""
        for proc in self.simulator.procs:
            if proc.poll() is not None:
                self.grade.notes.append('the grader\'s simulator had ended before the grader '
                                        'stopped it (exit status %d); see logs/simulator.log'
                                        % proc.returncode)
                continue
            for pid in (sandbox_children(proc.pid)[:1] if self.simulator_sandbox else [proc.pid]):
                try:
                    os.kill(pid, signal.SIGINT)
                except ProcessLookupError:
                    pass
        self.finish_stopping([(self.simulator, 'the simulator')])

    def stop_launch(self, group, name):
        """Stop a launch of the submission: roslaunch first, which stops its nodes, then its
        sandbox. Says in the notes if it had ended by itself, or left processes behind."""
        self.stop_launches([(group, name)])

    def stop_launches(self, launches):
        """Stop launches [(group, name)] together: each roslaunch gets SIGINT at once, and they
        stop their nodes side by side, within one grace time."""
        self.ask_to_stop_all(launches)
        self.finish_stopping(launches)

    def ask_to_stop_all(self, launches):
        for group, name in launches:
            self.ask_to_stop(group, name)

    def finish_stopping(self, launches):
        deadline = time.monotonic() + STOP_GRACE_S
        for group, _name in launches:
            for proc in group.procs:
                try:
                    proc.wait(max(0.0, deadline - time.monotonic()))
                except subprocess.TimeoutExpired:
                    pass
        for group, name in launches:
            try:
                group.stop()
            except OSError:
                pass
            logs = self.open_logs.get(id(group), [])
            self.close_logs(group)
            if id(group) in self.asked_while_running:
                self.asked_while_running.discard(id(group))
                self.note_required_death(name, logs)

    def note_required_death(self, name, logs):
        """A launch asked to stop while roslaunch was already stopping it, because a required
        node had died (roslaunch stops reporting deaths once asked to stop, so what its log
        says of one is from before)."""
        for log in logs:
            died = required_deaths(log.path, log.start)
            if died:
                self.grade.notes.append('%s had ended by itself before the grader stopped it '
                                        '(its required node %s had died, and roslaunch was '
                                        'still stopping the rest); see %s'
                                        % (name, died[0], self.log_label(log.path)))
                return

    def ask_to_stop(self, group, name):
        """SIGINT to the launch's roslaunch, inside its sandbox; notes on how it was found."""
        for proc in group.procs:
            if proc.poll() is not None:
                log = self.chaser_log if name == 'ball_chaser.launch' else self.world_log
                self.grade.notes.append('%s had ended by itself before the grader stopped it (exit '
                                        'status %d); see %s' % (name, proc.returncode,
                                                                self.log_label(log)))
                continue
            self.asked_while_running.add(id(group))
            if self.sandbox is None:
                continue
            inside = sandbox_children(proc.pid)
            if len(inside) > 1:
                self.grade.notes.append('%s left %d process%s running outside roslaunch (%s); '
                                        'they were killed with its sandbox' % (
                                            name, len(inside) - 1, '' if len(inside) == 2 else 'es',
                                            ', '.join(process_name(pid) for pid in inside[1:])))
            for pid in inside[:1]:
                try:
                    os.kill(pid, signal.SIGINT)
                except ProcessLookupError:
                    pass

    def close_logs(self, group):
        """Close a launch's logs; a log that was cut gets one note, which sums what each start
        of the launch wrote into it."""
        for log in self.open_logs.pop(id(group), []):
            cap = log.close()
            cut, total, starts = self.log_cuts.get(log.path, (0, 0, 0))
            self.log_cuts[log.path] = cut, total, starts = cut + cap.cut, total + cap.total, starts + 1
            if not cut:
                continue
            label = self.log_label(log.path)
            self.grade.notes[:] = [note for note in self.grade.notes
                                   if not note.startswith(label + ': ') or ' cut of ' not in note]
            if starts == 1:
                kept = 'the first and last %s kept' % size_text(cap.keep // 2)
            else:
                kept = '%d starts of the launch, %s kept in all' % (starts, size_text(self.log_limit))
            self.grade.notes.append('%s: %s cut of %s written (%s)' % (label, size_text(cut),
                                                                       size_text(total), kept))
