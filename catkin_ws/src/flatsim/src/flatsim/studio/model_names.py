"""Gazebo's names for the models the studio adds: inserted from a file, pasted, or made in an
editor. No ROS here."""
import itertools


def numbered_name(prefix, taken):
    """The first of prefix0, prefix1, ... not in taken."""
    return next(name for name in (prefix + str(number) for number in itertools.count())
                if name not in taken)


def unique_name(base, taken):
    """base itself if free, else the first of base_0, base_1, ... not in taken: how Gazebo
    names a model inserted from a file, and a pasted copy (base NAME_clone)."""
    return base if base not in taken else numbered_name(base + '_', taken)


def clone_name(source, taken):
    """Gazebo's name for a pasted copy: NAME_clone, then NAME_clone_0, NAME_clone_1, ..."""
    return unique_name(source + '_clone', taken)

