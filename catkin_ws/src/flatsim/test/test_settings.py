"""The simulator's ~seed and ~real_time_factor, checked without a master: the values
flatsim runs with, and a one-line error naming the parameter for any other."""
import math

import pytest

from flatsim import settings
from flatsim.errors import FlatsimError


@pytest.mark.parametrize('value, seed', [(0, 0), (7, 7), ('12', 12), (3.0, 3),
                                         (4294967295, 4294967295)])
def test_a_whole_seed_in_gazebos_range_is_taken(value, seed):
    assert settings.seed(value) == seed


@pytest.mark.parametrize('value, shown', [
    # roslaunch passes seed:=1e30 on as the string '1e30'.
    ('1e30', "'1e30'"), (1e30, '1e+30'), (-1, '-1'), (4294967296, '4294967296'), (0.5, '0.5'),
    (math.nan, 'nan'), (math.inf, 'inf'), ('abc', "'abc'"), (True, 'True'), ([1], '[1]'),
])
def test_any_other_seed_is_refused_naming_the_parameter_and_its_range(value, shown):
    with pytest.raises(FlatsimError) as caught:
        settings.seed(value)
    assert str(caught.value) == '~seed must be a whole number from 0 to 4294967295, got %s' % shown


@pytest.mark.parametrize('value, factor', [(0, 0.0), (0.0, 0.0), ('0', 0.0), (1, 1.0), (0.5, 0.5),
                                           ('2.5', 2.5), (0.001, 0.001), (1000, 1000.0)])
def test_zero_runs_as_fast_as_possible_and_a_factor_in_range_is_taken(value, factor):
    assert settings.real_time_factor(value) == factor


@pytest.mark.parametrize('value, shown', [
    (-1, '-1'), (math.nan, 'nan'), ('nan', "'nan'"), (1e308, '1e+308'), (math.inf, 'inf'),
    (-math.inf, '-inf'), (1e-300, '1e-300'), (1000.5, '1000.5'), ('fast', "'fast'"), (True, 'True'),
])
def test_any_other_real_time_factor_is_refused_naming_the_parameter_and_what_it_takes(value, shown):
    with pytest.raises(FlatsimError) as caught:
        settings.real_time_factor(value)
    assert str(caught.value) == ('~real_time_factor must be 0 (as fast as possible) or 0.001 to '
                                 '1000 sim seconds per wall second, got %s' % shown)
