"""What the grader's node hears of the run besides the model states: sim time (SimClock), the
camera's first frames of a trial (FrameWatch), and process_image's calls (CallCounter).
"""
import threading
import time

import rosgraph
import rospy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Image

from chase_tools.chase_graph import CAMERA_TOPIC, NEW_RUN_STAMP_S
from chase_tools.grading import course_service, probe, submission, trials
from chase_tools.grading.bounds import CALLS_KEPT, FORWARD_S, FRAME_WATCH_S, sim_wall_s


class CallCounter:
    """Serves /grader/command_robot: records each request of process_image, forwards it to drive_bot."""

    def __init__(self, clock):
        self.srv_type = course_service.course_drive_to_target()
        self.clock = clock
        self.calls = trials.RollingLog(CALLS_KEPT)     # (sim time, linear_x, angular_z)
        self.forwarding = False
        self.server = None
        self.advertise()

    def serve_as(self, srv_type):
        """Serve srv_type from now on: the submission's own type, when only its response differs
        from the course's (service_type.py)."""
        self.srv_type = srv_type
        self.advertise()

    def advertise(self):
        self.close()
        self.server = rospy.Service(submission.PROXY_SERVICE, self.srv_type, self.handle)

    def held_answer(self):
        """The answer to a call held back: the course's says so, another response is left at
        its fields' defaults."""
        if tuple(self.srv_type._response_class.__slots__) == ('msg_feedback',):
            return self.srv_type._response_class('held while drive_bot is tested')
        return self.srv_type._response_class()

    def close(self):
        if self.server is not None:
            self.server.shutdown()
            self.server = None

    def handle(self, req):
        self.calls.append((self.clock.now(), req.linear_x, req.angular_z))
        if not self.forwarding:
            return self.held_answer()
        try:
            # A master client of its own: each caller's connection has a thread of its own.
            uri = rosgraph.Master(rospy.get_name()).lookupService(submission.COURSE_SERVICE)
            return probe.call_service(uri,
                                      submission.COURSE_SERVICE, self.srv_type, req, FORWARD_S)
        except (probe.ProbeError, rosgraph.masterapi.Error, OSError) as error:
            raise rospy.ServiceException('drive_bot did not answer: %s' % error) from None


class SimClock:
    """Sim time from /clock, kept here so it is right whatever the node was started with."""

    def __init__(self):
        self.time = None
        self.after_reset = False
        self.changed = threading.Condition()
        rospy.Subscriber('/clock', Clock, self.on_clock, queue_size=10)

    def begin_run(self):
        """Sim time is about to go back to 0: until it has, report 0 and ignore later stamps,
        which may still be on their way from before the reset."""
        with self.changed:
            self.after_reset = True
            self.time = 0.0

    def on_clock(self, msg):
        stamp = msg.clock.to_sec()
        with self.changed:
            if self.after_reset:
                if stamp > NEW_RUN_STAMP_S:
                    return
                self.after_reset = False
            self.time = stamp
            self.changed.notify_all()

    def started(self):
        """False between begin_run() and the first /clock of the new run."""
        return not self.after_reset

    def now(self):
        return self.time if self.time is not None else 0.0

    def wait(self, seconds, alive, wall_limit=None):
        """Wait for seconds of sim time; False if the launches died or sim time stalled."""
        start = self.now()
        wall_deadline = time.monotonic() + (wall_limit or sim_wall_s(seconds))
        with self.changed:
            while self.now() - start < seconds:
                if not alive() or time.monotonic() > wall_deadline:
                    return False
                self.changed.wait(0.2)
        return True


class FrameWatch:
    """Looks at the camera's frames early in each trial: did the ball show (a pure-white pixel)?

    Only the first FRAME_WATCH_S of sim time, or until the ball has shown: a frame of the
    course camera is 2 MB, and the grader must not cost the chase its speed.
    """

    def __init__(self, clock):
        self.clock = clock
        self.subscriber = None
        self.armed = False
        self.frames = self.white_frames = 0
        self.lock = threading.Lock()

    def subscribe(self):
        """Before the trial starts, so that the connection is made by its first frame."""
        self.frames = self.white_frames = 0
        self.armed = False
        self.subscriber = rospy.Subscriber(CAMERA_TOPIC, Image, self.on_image, queue_size=1,
                                           buff_size=1 << 24)

    def begin(self):
        """The trial has started: frames of the new run count from now on."""
        self.armed = True

    def on_image(self, msg):
        if not (self.armed and self.clock.started()) or msg.header.stamp.to_sec() > FRAME_WATCH_S:
            return                      # a frame from before the reset
        if self.clock.now() > FRAME_WATCH_S:
            self.stop()
            return
        white = trials.has_white_pixel(msg.data, msg.width, msg.height, msg.step, msg.encoding)
        if white is None:
            return
        with self.lock:
            self.frames += 1
            self.white_frames += int(white)
        if white:
            self.stop()

    def stop(self):
        with self.lock:
            subscriber, self.subscriber = self.subscriber, None
        if subscriber is not None:
            subscriber.unregister()
