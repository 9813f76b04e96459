"""The simulator's run settings, checked as its parameters give them: the value
flatsim runs with, or a FlatsimError that names the parameter and says what it
takes. A launch file's value may come as a string. No ROS here.
"""
import math

from flatsim.errors import FlatsimError

# Gazebo's --seed is an unsigned 32-bit int.
MAX_SEED = 2 ** 32 - 1
# Real-time factors flatsim paces to; 0 runs as fast as possible. Slower than the
# lowest, one step of a course world would hold the clock for seconds; faster than
# the highest is beyond any machine, so it means "as fast as possible", which 0 says.
MIN_REAL_TIME_FACTOR = 0.001
MAX_REAL_TIME_FACTOR = 1000.0
REAL_TIME_FACTORS = ('0 (as fast as possible) or %g to %g sim seconds per wall second'
                     % (MIN_REAL_TIME_FACTOR, MAX_REAL_TIME_FACTOR))


def _shown(value):
    return '%g' % value if isinstance(value, float) else repr(value)


def _number(value):
    """value as a float, or None if it is not a number at all."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value)
    try:
        return float(str(value).strip())
    except ValueError:
        return None


def seed(value, name='~seed'):
    """The seed of the sensor noise: a whole number from 0 to MAX_SEED."""
    number = _number(value)
    whole = number is not None and math.isfinite(number) and number.is_integer()
    if not whole or not 0 <= number <= MAX_SEED:
        raise FlatsimError('%s must be a whole number from 0 to %d, got %s'
                           % (name, MAX_SEED, _shown(value)))
    return int(number)


def real_time_factor(value, name='~real_time_factor'):
    """Sim seconds per wall second; 0 runs as fast as possible."""
    number = _number(value)
    if number is None or not (number == 0.0 or MIN_REAL_TIME_FACTOR <= number <= MAX_REAL_TIME_FACTOR):
        raise FlatsimError('%s must be %s, got %s' % (name, REAL_TIME_FACTORS, _shown(value)))
    return number
