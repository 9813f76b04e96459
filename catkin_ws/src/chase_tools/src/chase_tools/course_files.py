"""Copy into DEST the files the course downloads for my_robot, for a machine
without the Internet: the Hokuyo mesh and the course's my_robot.gazebo.

  rosrun chase_tools course_files DEST            DEST is made if missing
  rosrun chase_tools course_files --force DEST    replace files already in DEST

Existing files are left alone unless --force is given. They live in
chase_tools rather than my_robot, so a student's own my_robot, which hides
the project's, does not hide them.
"""
import argparse
import os
import shutil
import sys

import rospkg

# (file in chase_tools' course/, where the course puts it in the student's my_robot)
COURSE_FILES = (
    ('hokuyo.dae', 'my_robot/meshes/hokuyo.dae'),
    ('my_robot.gazebo', 'my_robot/urdf/my_robot.gazebo'),
)


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog='course_files', description=__doc__.split('\n\n')[0].replace('\n', ' '),
        epilog='The course then has you place hokuyo.dae in my_robot/meshes/ and '
               'my_robot.gazebo in my_robot/urdf/.')
    parser.add_argument('dest', metavar='DEST', help='folder to copy the files into (made if missing)')
    parser.add_argument('--force', action='store_true', help='replace files that are already in DEST')
    return parser.parse_args(argv)


def fail(message):
    print('course_files: %s' % message, file=sys.stderr)
    return 1


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    dest = os.path.abspath(os.path.expanduser(args.dest))
    if os.path.exists(dest) and not os.path.isdir(dest):
        return fail('%s is a file, not a folder; give a folder to copy into' % dest)
    try:
        os.makedirs(dest, exist_ok=True)
    except OSError as error:
        return fail('cannot make the folder %s: %s' % (dest, error.strerror))
    course_dir = os.path.join(rospkg.RosPack().get_path('chase_tools'), 'course')
    targets = [(os.path.join(course_dir, source), os.path.join(dest, os.path.basename(source)), course)
               for source, course in COURSE_FILES]
    present = [target for _source, target, _course in targets if os.path.lexists(target)]
    if present and not args.force:
        return fail('%s already exist%s; nothing was copied (add --force to replace %s)'
                    % (', '.join(present), 's' if len(present) == 1 else '',
                       'it' if len(present) == 1 else 'them'))
    for source, target, course in targets:
        try:
            if os.path.islink(target):
                # Replace the link itself rather than write through it to wherever it points.
                os.remove(target)
            shutil.copyfile(source, target)
        except OSError as error:
            return fail('cannot write %s: %s' % (target, error.strerror))
        print('wrote %s  (the course downloads it to %s)' % (target, course))
    return 0
