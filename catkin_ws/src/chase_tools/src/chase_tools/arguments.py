"""argparse types shared by the chase tools' command lines (chase_demo, evaluate, grade,
report): a value that cannot work is an argument error when the command starts, never a
traceback or a failed run later."""
import argparse
import math
import os

MAX_PORT = 65535
# flatsim reads its seed as a ROS parameter, and XML-RPC carries 32-bit integers; placements
# take non-negative seeds only.
MAX_SEED = 2 ** 31 - 1


def number(kind, low=None, high=None, low_open=False):
    """An argparse type: a finite number of kind (int or float) within [low, high] (low excluded
    when low_open), or a clear error."""
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError('%r is not %s' % (
                text, 'a whole number' if kind is int else 'a number')) from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError('%r is not a finite number' % text)
        if low is not None and (value < low or (low_open and value == low)):
            raise argparse.ArgumentTypeError('%s must be %s %s' % (
                text, 'more than' if low_open else 'at least', _shown(low)))
        if high is not None and value > high:
            raise argparse.ArgumentTypeError('%s must be at most %s' % (text, _shown(high)))
        return value
    return parse


def _shown(bound):
    return '%d' % bound if isinstance(bound, int) else '%g' % bound


port = number(int, 1, MAX_PORT)
seed = number(int, 0, MAX_SEED)
positive = number(float, 0, low_open=True)
not_negative = number(float, 0)


def output_folder(text):
    """An argparse type: a folder that exists or can be made, and can be written to; it is made."""
    path = os.path.abspath(text)
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as error:
        raise argparse.ArgumentTypeError('cannot make the folder %s: %s' % (text, error.strerror)) from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError('cannot write into the folder %s' % text)
    return path
