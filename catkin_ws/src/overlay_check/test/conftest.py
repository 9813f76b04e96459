import pathlib
import sys

# Lets pytest import the module from the source tree without a built workspace.
sys.path.append(str(pathlib.Path(__file__).resolve().parent.parent / 'src'))
