"""Build packages in a throwaway catkin workspace on top of this one: an overlay.

The course builds a student's packages in ~/catkin_ws with this workspace's
devel space sourced underneath. The grader and the tests do the same in a
temporary folder:

    ws = Overlay(tmp_path / 'ws')
    ws.add(FIXTURES / 'simple_arm')
    result = ws.build()
    assert result.returncode == 0, result.stdout
    subprocess.run(['rosrun', 'simple_arm', 'arm_mover'], env=ws.env())

build() runs plain catkin_make, as a student types it. build_robustly() is
the grader's build (see its docstring). With a sandbox (sandbox.Sandbox) every
command runs inside it; catkin_make runs with the environment this process
has, which `source env.sh` has set up: the venv's python, this workspace's
devel space and env/bin/catkin_make first on PATH, exactly what a student's
terminal has.
"""
import os
import re
import shutil
import sys
import time
from dataclasses import dataclass, field
from typing import List

from chase_tools.grading.logcap import run_captured
from chase_tools.grading.sandbox_processes import end_sandbox
from chase_tools.grading.submission import package_dirs, read_package

BUILD_TIMEOUT_S = 900
DEFAULT_LOG_KEEP = 2 << 20
# GCC 12 names the header for some standard names:
#   note: 'std::string' is defined in header '<string>'; did you forget to '#include <string>'?
HEADER_NOTE = re.compile(r"note: '(?:std::)?([\w:]+)' is defined in header '<([\w./]+)>'")
# For others it only says the name is unknown:
#   error: 'accumulate' is not a member of 'std'
#   error: 'accumulate' was not declared in this scope
UNKNOWN_NAME = re.compile(r"error: '(?:std::)?(\w+)' (?:is not a member of 'std'|was not declared in this scope"
                          r"|in namespace 'std' does not name a (?:template )?type)")
# Standard names whose header older GCCs (Ubuntu 20.04's GCC 9) pulled in through
# other standard headers, and GCC 11 and 12 no longer do.
STD_HEADERS = {
    'numeric': ('accumulate', 'iota', 'inner_product', 'partial_sum', 'adjacent_difference',
                'reduce', 'gcd', 'lcm'),
    'algorithm': ('sort', 'stable_sort', 'find', 'find_if', 'count', 'count_if', 'min_element',
                  'max_element', 'minmax_element', 'transform', 'reverse', 'fill', 'copy',
                  'copy_if', 'remove', 'remove_if', 'unique', 'any_of', 'all_of', 'none_of',
                  'for_each', 'clamp', 'lower_bound', 'upper_bound', 'binary_search', 'nth_element'),
    'limits': ('numeric_limits',),
    'stdexcept': ('runtime_error', 'logic_error', 'invalid_argument', 'out_of_range',
                  'domain_error', 'length_error', 'overflow_error', 'range_error'),
    'memory': ('unique_ptr', 'shared_ptr', 'weak_ptr', 'make_shared', 'make_unique'),
    'functional': ('function', 'bind', 'ref', 'cref', 'hash', 'plus', 'minus', 'greater', 'less'),
    'utility': ('pair', 'make_pair', 'move', 'swap', 'forward'),
    'thread': ('thread', 'this_thread'),
    'mutex': ('mutex', 'lock_guard', 'unique_lock', 'recursive_mutex'),
    'sstream': ('stringstream', 'ostringstream', 'istringstream'),
    'iomanip': ('setw', 'setprecision', 'setfill', 'fixed'),
    'cmath': ('abs', 'fabs', 'sqrt', 'pow', 'atan2', 'floor', 'ceil', 'round', 'hypot', 'isnan',
              'isfinite'),
    'cstdint': ('uint8_t', 'uint16_t', 'uint32_t', 'uint64_t', 'int8_t', 'int16_t', 'int32_t',
                'int64_t'),
    'cstring': ('memcpy', 'memset', 'strlen', 'strcmp'),
    'array': ('array',),
    'chrono': ('chrono',),
    'tuple': ('tuple', 'make_tuple', 'tie', 'get'),
}
HEADER_OF = {name: header for header, names in STD_HEADERS.items() for name in names}
FAILED_GOAL = re.compile(r'^make: \*\*\* \[Makefile:\d+: ([\w.-]+)\] Error', re.M)
ERROR_LINE = re.compile(r'(error:|Error|ERROR|\*\*\*|undefined reference|No such file)')
MAX_ERROR_LINES = 12
HEADER_RETRIES = 2
CMAKE_MESSAGE_LINES = 4


@dataclass
class BuildOutcome:
    """What build_robustly did: its steps in words, and whether the last build passed."""
    passed: bool
    steps: List[str] = field(default_factory=list)
    message_targets: List[str] = field(default_factory=list)
    forced_headers: List[str] = field(default_factory=list)
    error_lines: List[str] = field(default_factory=list)
    log: str = ''
    timed_out: bool = False        # the build's time ran out
    cut: int = 0                   # bytes of output not kept (see logcap)


def error_lines(output, limit=MAX_ERROR_LINES, pattern=ERROR_LINE):
    """The lines of a log that say what went wrong, first ones first, each once.

    CMake puts its message on the indented lines after "CMake Error at ...": they come too.
    """
    lines = []
    following = 0
    for line in output.splitlines():
        line = line.rstrip()
        if following and line.startswith(' ') and line.strip():
            lines.append(line)
            following -= 1
        elif pattern.search(line) and line not in lines:
            lines.append(line)
            following = CMAKE_MESSAGE_LINES if line.startswith('CMake Error') else 0
        else:
            following = 0 if line.strip() else following
        if len(lines) >= limit:
            break
    return lines[:limit]


def failed_goal(output):
    """The goal of the top-level make that failed (`make: *** [Makefile:NNN: goal] Error 2`), or
    None."""
    found = FAILED_GOAL.findall(output)
    return found[-1] if found else None


def missing_headers(output):
    """{header: [names]}: standard headers the compiler says are missing, and the names that want them."""
    found = {}

    def add(name, header):
        names = found.setdefault(header, [])
        if name not in names:
            names.append(name)

    for name, header in HEADER_NOTE.findall(output):
        add(name, header)
    for name in UNKNOWN_NAME.findall(output):
        if name in HEADER_OF:
            add(name, HEADER_OF[name])
    return dict(sorted(found.items()))


class Overlay:
    def __init__(self, root, sandbox=None):
        self.root = os.fspath(root)
        self.src = os.path.join(self.root, 'src')
        os.makedirs(self.src, exist_ok=True)
        self.sandbox = sandbox
        self._env = None
        # The names of the packages in src, read when they were copied there: once the
        # build has run, src is the submission's to change (a link in place of a folder),
        # and the grader, root, does not read it again.
        self.packages = set()

    def add(self, package_dir, name=None):
        """Copy a package (or a folder of packages) into src; returns its path there."""
        target = os.path.join(self.src, name or os.path.basename(os.fspath(package_dir).rstrip('/')))
        shutil.copytree(package_dir, target, symlinks=True)
        for path in package_dirs(target):
            try:
                self.packages.add(read_package(path).name)
            except ValueError:
                continue
        return target

    def _run(self, cmd, env=None, timeout=BUILD_TIMEOUT_S):
        env = dict(os.environ if env is None else env)
        # Plain ASCII quotes in compiler messages, which missing_headers reads.
        env['LC_ALL'] = 'C'
        keep, on_stop = DEFAULT_LOG_KEEP, None
        if self.sandbox is not None:
            cmd, env = self.sandbox.wrap(cmd, env, cwd=self.root)
            confinement = self.sandbox.confinement
            keep, on_stop = confinement.limits.log, lambda: end_sandbox(confinement)
        result = run_captured(cmd, env=env, timeout=max(1.0, timeout), keep=keep, on_stop=on_stop)
        if result.timed_out:
            result.returncode = -9
            result.stdout += '\nERROR: timed out after %d s' % timeout
        return result

    def catkin_make(self, *args, env=None, timeout=BUILD_TIMEOUT_S):
        """catkin_make -C root [args]: a CompletedProcess with stdout and stderr together."""
        self._env = None
        # catkin writes the interpreter it finds into the devel space; it must be this one.
        return self._run(['catkin_make', '-C', self.root,
                          '-DPYTHON_EXECUTABLE=%s' % sys.executable] + list(args),
                         env=env, timeout=timeout)

    def build(self, *args, env=None):
        """Plain catkin_make [args] in the overlay, as a student types it."""
        return self.catkin_make(*args, env=env)

    def message_targets(self, env=None, timeout=BUILD_TIMEOUT_S):
        """The overlay packages' <pkg>_generate_messages targets, after a configure."""
        names = self.packages
        result = self._run(['make', '-C', os.path.join(self.root, 'build'), 'help'], env=env,
                           timeout=timeout)
        listed = {line.strip().lstrip('.').strip() for line in result.stdout.splitlines()}
        return sorted('%s_generate_messages' % name for name in names
                      if '%s_generate_messages' % name in listed)

    def build_robustly(self, env=None, timeout=BUILD_TIMEOUT_S):
        """The grader's build, with the two fixes students need here, each said in steps:

        1. Configure, then build every package's message targets before anything
           else. A CMakeLists that forgets add_dependencies on its own generated
           headers then builds anyway; plain catkin_make fails on it at random
           (on two cores, every time).
        2. If the compiler says a standard name is used without its header
           (code that built on Ubuntu 20.04, whose headers included more of each
           other), build again with those headers forced in (-include).

        timeout: wall seconds for the whole build, every step together.
        """
        outcome = BuildOutcome(False)
        logs = []
        deadline = time.monotonic() + timeout

        def left():
            return deadline - time.monotonic()

        def step(title, result):
            logs.append('==== %s (exit %d, %.1f s)\n%s' % (title, result.returncode,
                                                         getattr(result, 'wall_s', 0.0), result.stdout))
            outcome.cut += getattr(result, 'cut', 0)
            outcome.timed_out = outcome.timed_out or getattr(result, 'timed_out', False) or left() <= 0
            return result.returncode == 0 and not outcome.timed_out

        def fail(result, what):
            if outcome.timed_out:
                what = 'the build did not finish within %g s' % timeout
            outcome.error_lines = error_lines(result.stdout) or result.stdout.strip().splitlines()[-5:]
            outcome.steps.append(what)
            outcome.log = '\n'.join(logs)
            return outcome

        configure = self.catkin_make('cmake_check_build_system', env=env, timeout=left())
        if not step('configure: catkin_make cmake_check_build_system', configure):
            return fail(configure, 'CMake configuration failed')
        outcome.message_targets = self.message_targets(env, timeout=left())
        # One make, its goals one after the other (CMake's top-level Makefile is .NOTPARALLEL):
        # the message targets first, then everything.
        goals = outcome.message_targets + ['all'] if outcome.message_targets else []
        full = self.catkin_make(*goals, env=env, timeout=left())
        title = 'build: catkin_make %s' % ' '.join(goals) if goals else 'build: catkin_make'
        built = step(title, full)
        if outcome.message_targets:
            if not built and failed_goal(full.stdout) in outcome.message_targets:
                return fail(full, 'building the message targets (%s) failed'
                            % ', '.join(outcome.message_targets))
            outcome.steps.append('message targets built first: %s' % ', '.join(outcome.message_targets))
        else:
            outcome.steps.append('no message targets to build first')
        if built:
            outcome.passed = True
            outcome.steps.append('catkin_make built every package')
            outcome.log = '\n'.join(logs)
            return outcome
        result, forced = full, {}
        for _attempt in range(HEADER_RETRIES if not outcome.timed_out else 0):
            wanted = missing_headers(result.stdout)
            if not wanted or set(wanted) <= set(forced):
                break
            for header, names in wanted.items():
                forced.setdefault(header, [])
                forced[header] += [name for name in names if name not in forced[header]]
            flags = ' '.join('-include %s' % header for header in sorted(forced))
            outcome.forced_headers = sorted(forced)
            outcome.steps.append(
                'the build failed for want of standard headers that Ubuntu 20.04\'s compiler '
                'included through others (%s); retried with them forced in (%s)'
                % ('; '.join('<%s> for %s' % (h, ', '.join(n)) for h, n in sorted(forced.items())),
                   flags))
            result = self.catkin_make('-DCMAKE_CXX_FLAGS=%s' % flags, env=env, timeout=left())
            if step('retry: catkin_make -DCMAKE_CXX_FLAGS="%s"' % flags, result):
                outcome.passed = True
                outcome.steps.append('the retry built every package')
                outcome.log = '\n'.join(logs)
                return outcome
            if outcome.timed_out:
                break
        return fail(result, 'catkin_make failed' if not forced
                    else 'the retry with the headers forced in failed too')

    def env(self):
        """The environment after `source devel/setup.bash` in the overlay (env hooks run sandboxed)."""
        if self._env is None:
            setup = os.path.join(self.root, 'devel', 'setup.bash')
            result = self._run(['bash', '-c', 'source "$0" >/dev/null 2>&1 && env -0', setup],
                               timeout=60)
            if result.returncode != 0:
                raise RuntimeError('sourcing %s failed: %s' % (setup, result.stdout[-500:]))
            items = result.stdout.split('\0')
            self._env = dict(item.split('=', 1) for item in items if '=' in item)
            if self.sandbox is not None:
                for name in ('HOME', 'ROS_HOME', 'TMPDIR'):
                    self._env.pop(name, None)
        return dict(self._env)

