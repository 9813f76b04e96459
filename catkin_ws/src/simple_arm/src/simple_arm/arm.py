"""The lessons' arm logic without ROS: the safe zone clamp, the sine sweep, and look_away's tests."""
import math

# look_away's tolerance for "the joints did not move" between two joint_states (rad).
STILL_TOLERANCE = 0.0005
# The largest joint angle arm_mover sends (rad), about 160,000 turns, where a double still
# resolves 1e-10 rad. Far beyond it the joint's position is lost to rounding when the
# controller subtracts it from the target: the error never shrinks and a continuous joint
# spins without end.
MAX_TARGET_ANGLE = 1e6


def sweep_angle(elapsed_seconds):
    """simple_mover's command: a 10 s sine between -pi/2 and pi/2, on whole seconds as in the course."""
    return math.sin(2 * math.pi * 0.1 * int(elapsed_seconds)) * (math.pi / 2)


def clamp_at_boundaries(requested, bounds):
    """Clamp each requested joint angle into its (min, max); returns (angles, warnings)."""
    clamped, warnings = [], []
    for number, (value, (low, high)) in enumerate(zip(requested, bounds), start=1):
        if value < low or value > high:
            inside = min(max(value, low), high)
            warnings.append('j%d is out of bounds, valid range (%1.2f,%1.2f), clamping to: %1.2f'
                            % (number, low, high, inside))
            value = inside
        clamped.append(value)
    return clamped, warnings


def too_large_to_track(angles):
    """Why these joint angles cannot be sent (one beyond MAX_TARGET_ANGLE either way), or None."""
    problems = ['j%d=%g' % (number, value) for number, value in enumerate(angles, start=1)
                if not abs(value) <= MAX_TARGET_ANGLE]
    if not problems:
        return None
    return '%s: too large to track, the limit is %g rad either way' % (', '.join(problems),
                                                                      MAX_TARGET_ANGLE)


def is_uniform(data):
    """Every byte of the image equals the first (look_away's test for looking at the sky)."""
    data = bytes(data)
    return len(data) == 0 or data.count(data[0]) == len(data)


class MotionWatch:
    """look_away's moving state: the joints moved since the last position it kept."""

    def __init__(self):
        self.last = [0.0, 0.0]
        self.moving = False

    def update(self, positions):
        current = list(positions[:2])
        if len(current) < 2:
            return self.moving
        if all(abs(now - before) < STILL_TOLERANCE for now, before in zip(current, self.last)):
            self.moving = False
        else:
            self.moving = True
            self.last = current
        return self.moving
