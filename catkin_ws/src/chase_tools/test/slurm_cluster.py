"""A one-node Slurm cluster of this machine, for tests: munged, slurmctld and slurmd from
Debian's packages (slurm-wlm, munge), each with its own files in one folder.

    with SlurmCluster() as cluster:
        subprocess.run(['sbatch', ...], env=cluster.env())

The configuration is written at run time: this host's name and the CPUs and
memory slurmd reports (slurmd -C), free ports, a fresh munge key, state and
logs in the folder. The daemons run in the foreground as children of this
process and are stopped, with every job cancelled, when the block ends.
"""
import os
import re
import shutil
import socket
import subprocess
import tempfile
import time

COMMANDS = ('munged', 'slurmctld', 'slurmd', 'sbatch', 'squeue', 'scontrol', 'scancel', 'sinfo')
PARTITION = 'grading'
STARTUP_TIMEOUT_S = 60.0
STOP_TIMEOUT_S = 20.0
# Slurm's KillWait (30 s) and then some, for cancelled jobs to end before the daemons do.
CANCEL_TIMEOUT_S = 60.0


def command(name):
    """The full path of a Slurm or munge program (the daemons live in sbin)."""
    return shutil.which(name, path=os.pathsep.join([os.environ.get('PATH', ''), '/usr/sbin', '/sbin']))


class Unavailable(Exception):
    """This machine cannot run a Slurm cluster at all; the message says why."""


def free_port():
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


def why_unavailable():
    """None if this machine can run the daemons, else why not."""
    missing = [name for name in COMMANDS if command(name) is None]
    if missing:
        return ('%s not installed (Debian packages slurm-wlm and munge; ./setup.sh installs them)'
                % ', '.join(missing))
    if os.geteuid() != 0:
        return 'slurmd starts each job as its user, which takes root'
    return None


def node_line():
    """slurmd -C's description of this machine (NodeName=... CPUs=... RealMemory=...)."""
    result = subprocess.run([command('slurmd'), '-C'], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, timeout=30, check=False)
    line = result.stdout.splitlines()[0] if result.stdout else ''
    if result.returncode != 0 or not line.startswith('NodeName='):
        raise Unavailable('slurmd -C cannot describe this machine: %s' % result.stdout.strip())
    return line


class SlurmCluster:
    def __init__(self):
        self.folder = None
        self.procs = []
        self.node = None

    def path(self, *names):
        return os.path.join(self.folder, *names)

    def env(self):
        return dict(os.environ, SLURM_CONF=self.path('slurm.conf'))

    def start(self):
        problem = why_unavailable()
        if problem:
            raise Unavailable(problem)
        line = node_line()
        self.node = re.match(r'NodeName=(\S+)', line).group(1)
        # munged wants every folder above its socket searchable by all, which a test's tmp_path is not.
        self.folder = tempfile.mkdtemp(prefix='grade_slurm_')
        os.chmod(self.folder, 0o755)
        for name in ('munge', 'state', 'spool'):
            os.makedirs(self.path(name), mode=0o755)
        with open(self.path('munge', 'munge.key'), 'wb') as stream:
            stream.write(os.urandom(1024))
        os.chmod(self.path('munge', 'munge.key'), 0o400)
        socket_path = self.path('munge', 'munge.socket')
        self.spawn('munged', ['munged', '--foreground', '--socket=' + socket_path,
                              '--key-file=' + self.path('munge', 'munge.key'),
                              '--log-file=' + self.path('munged.log'),
                              '--pid-file=' + self.path('munge', 'munged.pid'),
                              '--seed-file=' + self.path('munge', 'munged.seed')])
        self.wait_for(lambda: os.path.exists(socket_path), 'munged to make its socket', 'munged')
        with open(self.path('slurm.conf'), 'w') as stream:
            stream.write(self.config(line, socket_path))
        self.spawn('slurmctld', ['slurmctld', '-D', '-f', self.path('slurm.conf')])
        self.spawn('slurmd', ['slurmd', '-D', '-f', self.path('slurm.conf'), '-N', self.node])
        self.wait_for(self.node_idle, 'node %s to be idle' % self.node, 'slurmd')
        return self

    def config(self, line, socket_path):
        node = line + ' NodeAddr=127.0.0.1 State=UNKNOWN'
        settings = [
            ('ClusterName', 'gradetest'),
            ('SlurmctldHost', '%s(127.0.0.1)' % self.node),
            ('SlurmctldPort', free_port()),
            ('SlurmdPort', free_port()),
            ('SlurmUser', 'root'),
            ('AuthType', 'auth/munge'),
            ('CredType', 'cred/munge'),
            ('AuthInfo', 'socket=' + socket_path),
            ('StateSaveLocation', self.path('state')),
            ('SlurmdSpoolDir', self.path('spool')),
            ('SlurmctldPidFile', self.path('slurmctld.pid')),
            ('SlurmdPidFile', self.path('slurmd.pid')),
            ('SlurmctldLogFile', self.path('slurmctld.log')),
            ('SlurmdLogFile', self.path('slurmd.log')),
            # No cgroups: the machine's cgroup tree belongs to its host.
            ('ProctrackType', 'proctrack/linuxproc'),
            ('TaskPlugin', 'task/none'),
            ('JobAcctGatherType', 'jobacct_gather/none'),
            ('AccountingStorageType', 'accounting_storage/none'),
            ('SelectType', 'select/cons_tres'),
            ('SelectTypeParameters', 'CR_Core'),
            ('MpiDefault', 'none'),
            ('MailProg', shutil.which('true')),
            ('ReturnToService', 2),
        ]
        lines = ['%s=%s' % pair for pair in settings]
        lines += [node, 'PartitionName=%s Nodes=%s Default=YES MaxTime=INFINITE State=UP'
                  % (PARTITION, self.node)]
        return '\n'.join(lines) + '\n'

    def spawn(self, name, cmd):
        log = open(self.path(name + '.out'), 'w')
        cmd = [command(cmd[0])] + cmd[1:]
        self.procs.append((name, subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                                  env=self.env(), start_new_session=True), log))

    def node_idle(self):
        result = subprocess.run(['sinfo', '--noheader', '--Node', '--format', '%T'], env=self.env(),
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                timeout=30, check=False)
        return result.stdout.strip() == 'idle'

    def wait_for(self, ready, what, log_of):
        deadline = time.monotonic() + STARTUP_TIMEOUT_S
        while time.monotonic() < deadline:
            dead = [name for name, proc, _log in self.procs if proc.poll() is not None]
            if dead:
                break
            if ready():
                return
            time.sleep(0.5)
        raise RuntimeError('waited in vain for %s:\n%s' % (what, self.logs()))

    def logs(self):
        text = []
        for name in ('munged.out', 'munged.log', 'slurmctld.out', 'slurmctld.log', 'slurmd.out',
                     'slurmd.log'):
            if os.path.exists(self.path(name)):
                with open(self.path(name), errors='replace') as stream:
                    text.append('== %s\n%s' % (name, ''.join(stream.readlines()[-20:])))
        return '\n'.join(text)

    def jobs(self):
        """The ids of the jobs that have not ended, an array's tasks each on its own."""
        result = subprocess.run(['squeue', '--noheader', '--array', '--format', '%i'], env=self.env(),
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                timeout=30, check=False)
        return result.stdout.split()

    def cancel_all(self):
        subprocess.run(['scancel', '--partition', PARTITION], env=self.env(), stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, timeout=30, check=False)
        deadline = time.monotonic() + CANCEL_TIMEOUT_S
        while self.jobs() and time.monotonic() < deadline:
            time.sleep(1)

    def stop(self):
        if [name for name, proc, _log in self.procs if name == 'slurmd' and proc.poll() is None]:
            self.cancel_all()
        for _name, proc, log in reversed(self.procs):
            proc.terminate()
            try:
                proc.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            log.close()
        self.procs = []
        if self.folder:
            shutil.rmtree(self.folder, ignore_errors=True)

    def __enter__(self):
        try:
            return self.start()
        except BaseException:
            self.stop()
            raise

    def __exit__(self, *_exc):
        self.stop()
