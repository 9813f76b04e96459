import pathlib
import sys

# Lets pytest import the pure modules from the source tree, with or without a built workspace.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / 'src'))
