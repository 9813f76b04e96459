"""The course's DriveToTarget, whatever workspace the teacher's shell has sourced.

A student's own ball_chaser, sourced in the shell that runs grade, would
otherwise be imported in its place, and the grader would then judge a
submission's service against the student's own definition.
"""
import importlib.util
import os

# float64 linear_x, float64 angular_z --- string msg_feedback
COURSE_MD5 = 'c8652349d2a34a90a09475339e2a93d9'
# This checkout's generated code: catkin_ws/devel beside catkin_ws/src/chase_tools.
PROJECT_GENERATED = os.path.join(
    os.path.dirname(os.path.abspath(__file__)), *(['..'] * 5),
    'devel', 'lib', 'python3', 'dist-packages', 'ball_chaser', 'srv', '_DriveToTarget.py')


class CourseServiceMissing(Exception):
    pass


def course_drive_to_target():
    """The DriveToTarget service class with the course's definition."""
    try:
        from ball_chaser.srv import DriveToTarget
        if DriveToTarget._md5sum == COURSE_MD5:
            return DriveToTarget
    except ImportError:
        pass
    path = os.path.normpath(PROJECT_GENERATED)
    if os.path.isfile(path):
        spec = importlib.util.spec_from_file_location('chase_tools_course_drive_to_target', path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        if module.DriveToTarget._md5sum == COURSE_MD5:
            return module.DriveToTarget
    raise CourseServiceMissing(
        "the course's ball_chaser/DriveToTarget (md5 %s) is neither importable nor built at %s; "
        "run ./setup.sh" % (COURSE_MD5, path))
