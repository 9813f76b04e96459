import pathlib
import sys

# Lets pytest import the pure modules from the source tree without a built workspace.
# Appended, not prepended: with the devel space on the path, its turtlesim
# package must win, because only it also holds the generated messages.
sys.path.append(str(pathlib.Path(__file__).resolve().parent.parent / 'src'))
