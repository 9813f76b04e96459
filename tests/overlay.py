"""Build packages in a throwaway catkin workspace on top of this one.

The grader's builder, chase_tools.grading.overlay.Overlay, is the one helper:

    ws = Overlay(tmp_path / 'ws')
    ws.add(FIXTURES / 'simple_arm')
    result = ws.build()
    assert result.returncode == 0, result.stdout
    subprocess.run(['rosrun', 'simple_arm', 'arm_mover'], env=ws.env())

build() runs catkin_make with the environment this process runs in, which
`source env.sh` has set up: the venv's python, this workspace's devel space
and env/bin/catkin_make first on PATH, exactly what a student's terminal has.
"""
from chase_tools.grading.overlay import BUILD_TIMEOUT_S, Overlay  # noqa: F401
