"""Wrenches applied to bodies over a span of sim time, as gazebo_ros schedules them.

gazebo_ros's apply_body_wrench queues a job that sets the link's force and
torque before every physics step from start_time until start_time + duration
(forever when the duration is negative), and drops the job once that time
has passed. flatsim has one rigid body per model: a wrench on a link pushes
the model's body at that link's origin. Forces along z and torques about x
and y have nothing to act on in the plane and are left out. No ROS here.
"""
import math
from dataclasses import dataclass
from typing import Tuple

from flatsim.errors import FlatsimError

# Slack on time comparisons: jobs start and end on step boundaries given in
# nanoseconds, while sim time is a sum of float steps.
TIME_SLACK = 1e-9


@dataclass
class WrenchJob:
    body: str                              # scoped link name, as clear_body_wrenches names it
    model: str
    offset: Tuple[float, float]            # link origin in the model frame (x, y)
    force: Tuple[float, float, float]      # N, world frame
    torque: Tuple[float, float, float]     # N*m, world frame
    start: float                           # s of sim time
    duration: float                        # s; negative means until cleared

    def active(self, now):
        return now + TIME_SLACK >= self.start and (
            self.duration < 0 or now <= self.start + self.duration + TIME_SLACK)

    def expired(self, now):
        return self.duration >= 0 and now > self.start + self.duration + TIME_SLACK


class Wrenches:
    def __init__(self):
        self.jobs = []

    def add(self, job):
        values = job.force + job.torque + (job.start, job.duration)
        if not all(math.isfinite(v) for v in values):
            raise FlatsimError('wrench, start and duration must be finite numbers')
        self.jobs.append(job)

    def clear(self, body):
        self.jobs = [job for job in self.jobs if job.body != body]

    def clear_model(self, model):
        """Drop every wrench on the model's links; returns the scoped link names they were on."""
        dropped = sorted({job.body for job in self.jobs if job.model == model})
        self.jobs = [job for job in self.jobs if job.model != model]
        return dropped

    def apply(self, sim):
        """Push each body whose wrench is due now; forget the jobs whose time is over."""
        if not self.jobs:
            return
        now = sim.time
        for job in self.jobs:
            model = sim.models.get(job.model)
            if job.active(now) and model is not None and model.handle is not None:
                sim.physics.apply_force(model.handle, job.force[:2], job.offset, job.torque[2])
        self.jobs = [job for job in self.jobs if not job.expired(now)]
