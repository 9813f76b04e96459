"""The rubric's checks of the nodes: sensors, drive_bot_service, stops_without_ball and
process_image_calls (world_launches is world_check.py's, chase is chase.py's)."""
import time

import rospy
from sensor_msgs.msg import Image, LaserScan

from chase_tools import chase_graph
from chase_tools.chase_graph import CAMERA_TOPIC
from chase_tools.grading import course_service, probe, service_type, submission, trials
from chase_tools.grading.bounds import (DRIVE_CALL_S, POLL_S, REACT_S, SENSORS_WALL_S, SET_OFF_WALL_S,
                                        STATES_KEPT, WATCH_S)
from chase_tools.grading.guard import moved, tampered


SCAN_TOPIC = '/scan'
DRIVE_PROBE = (0.25, -0.35)    # a request no controller sends by chance
FLOAT_TOLERANCE = 1e-4         # C++ nodes often pass the request through float
ANSWER_NOTED_S = 0.05          # an answer that took this much sim time or more says so
COMMAND_WAIT_S = 2.0           # wall seconds after the answer for the asked command to show
STILL_SPEED = 0.01             # m/s and rad/s: a command this small counts as stopped
STILL_DISTANCE_M = 0.05
STILL_TURN_RAD = 0.05


class Checks:
    """The session's checks of the submission's nodes; a part of the session's own world."""

    # -- sensors ------------------------------------------------------------------------------
    def check_sensors(self):
        if not self.world_up():
            self.grade.set('sensors', False, 'not run: the world did not launch')
            return
        chase_graph.SimControl().unpause()
        got = {}

        def keep(name):
            def callback(msg):
                got.setdefault(name, msg)
            return callback
        subs = [rospy.Subscriber(CAMERA_TOPIC, Image, keep('camera'), queue_size=1),
                rospy.Subscriber(SCAN_TOPIC, LaserScan, keep('scan'), queue_size=1)]
        deadline = time.monotonic() + SENSORS_WALL_S
        while len(got) < 2 and time.monotonic() < deadline and self.world.alive():
            time.sleep(POLL_S)
        for sub in subs:
            sub.unregister()
        parts, passed = [], True
        if 'camera' in got:
            image = got['camera']
            parts.append('camera %s %dx%d %s' % (CAMERA_TOPIC, image.width, image.height,
                                                 image.encoding))
        else:
            passed = False
            parts.append('no image on %s (image topics: %s)'
                         % (CAMERA_TOPIC, ', '.join(self.topics_of('sensor_msgs/Image')) or 'none'))
        if 'scan' in got:
            scan = got['scan']
            parts.append('lidar %s %d beams over %.2f..%.2f rad, %.2f-%.1f m'
                         % (SCAN_TOPIC, len(scan.ranges), scan.angle_min, scan.angle_max,
                            scan.range_min, scan.range_max))
        else:
            passed = False
            parts.append('no scan on %s (laser topics: %s)'
                         % (SCAN_TOPIC, ', '.join(self.topics_of('sensor_msgs/LaserScan')) or 'none'))
        self.grade.set('sensors', passed, '; '.join(parts))

    def topics_of(self, msg_type):
        try:
            return sorted(name for name, kind in self.master.getPublishedTopics('') if kind == msg_type)
        except Exception:  # noqa: BLE001 - only for the evidence
            return []

    # -- drive_bot_service --------------------------------------------------------------------
    def check_drive_bot(self):
        uri = self.service_uri(submission.COURSE_SERVICE)
        if uri is None:
            offered = self.chaser_services()
            self.grade.set('drive_bot_service', False,
                           '%s is not served; the submission\'s nodes serve %s'
                           % (submission.COURSE_SERVICE, ', '.join(offered) or 'nothing'),
                           self.excerpt(self.chaser_log))
            return
        try:
            headers = probe.service_headers(uri, submission.COURSE_SERVICE)
        except probe.ProbeError as error:
            self.grade.set('drive_bot_service', False, 'the service does not answer: %s' % error,
                           self.excerpt(self.chaser_log))
            return
        course_type = course_service.course_drive_to_target()
        kind, md5 = headers.get('type', '?'), headers.get('md5sum', '?')
        srv_type, own = course_type, None
        if md5 != course_type._md5sum:
            own = self.own_service(headers)
            other = ('the service has type %s (md5 %s), not the course\'s ball_chaser/'
                     'DriveToTarget (float64 linear_x, float64 angular_z -> string '
                     'msg_feedback, md5 %s)' % (kind, md5, course_type._md5sum))
            if isinstance(own, service_type.ServiceTypeError):
                self.grade.set('drive_bot_service', False,
                               '%s; its own definition could not be read: %s' % (other, own))
                return
            if not service_type.has_course_request(own):
                self.grade.set('drive_bot_service', False,
                               '%s; its request (%s) has %s, not the course\'s %s'
                               % (other, own.source, service_type.fields_text(own.request),
                                  service_type.fields_text(service_type.COURSE_REQUEST)))
                return
            self.note_own_response(own)
            counted = self.counter is not None and self.counter.srv_type._md5sum == md5
            srv_type = self.counter.srv_type if counted else service_type.service_class(own)
        self.wait_for_cmd_publishers()
        # Sim time runs, as it always does in Gazebo: a handler may wait on it (ros::Duration::sleep).
        sim = chase_graph.SimControl() if self.models is not None and self.alive() else None
        try:
            if sim is not None:
                sim.unpause()
        except rospy.ServiceException as error:
            # A node of the submission took the simulator's name (the guard says which).
            self.grade.not_judged('drive_bot_service', 'the simulator did not answer, so sim time '
                                  'could not run for the probe: %s' % error)
            return
        try:
            self.probe_drive_bot(srv_type, own)
        finally:
            if sim is not None:
                try:
                    sim.pause()
                except rospy.ServiceException:
                    pass    # said by the next step that needs the simulator

    def probe_drive_bot(self, srv_type, own=None):
        """Each request must come out on /cmd_vel as asked. Other commands may come meanwhile
        (a node that sends a stop first, or another publisher of /cmd_vel): the one that
        matches counts, if it comes within COMMAND_WAIT_S of the answer. own: the submission's
        service_type.ServiceDefinition when srv_type is its own, not the course's."""
        results = []
        for request in (DRIVE_PROBE, (0.0, 0.0)):
            # A node's first message can leave before a subscriber has connected; ask twice.
            for _attempt in range(2):
                seen = len(self.cmd)
                asked = self.clock.now()
                try:
                    answer = self.call_drive_bot(srv_type, request, DRIVE_CALL_S)
                except rospy.ServiceException as error:
                    self.grade.set('drive_bot_service', False, 'calling it with linear_x %g, '
                                   'angular_z %g (sim time running) failed: %s'
                                   % (request[0], request[1], error),
                                   self.excerpt(self.chaser_log))
                    return
                waited = self.clock.now() - asked
                deadline = time.monotonic() + COMMAND_WAIT_S
                match = None
                while match is None and time.monotonic() < deadline:
                    match = trials.matching_command(self.cmd.since(seen), request, FLOAT_TOLERANCE)
                    time.sleep(0.02)
                published = self.cmd.since(seen)
                if match is not None:
                    break
            if not published:
                self.grade.set('drive_bot_service', False,
                               'a call with linear_x %g, angular_z %g answered "%s" but nothing came '
                               'out on /cmd_vel' % (request[0], request[1],
                                                    service_type.answer_text(answer)))
                return
            if match is None:
                shown = ', '.join('(%g, %g)' % command[1:] for command in published[-3:])
                self.grade.set('drive_bot_service', False,
                               'a call with linear_x %g, angular_z %g put %d command%s on /cmd_vel '
                               'within %g s, none of them as asked (linear.x, angular.z: %s%s)'
                               % (request[0], request[1], len(published),
                                  '' if len(published) == 1 else 's', COMMAND_WAIT_S,
                                  '... ' if len(published) > 3 else '', shown))
                return
            _t, linear, angular = match
            others = len(published) - 1
            results.append('(%g, %g) -> /cmd_vel (%g, %g), answer "%s"%s%s'
                           % (request[0], request[1], linear, angular, service_type.answer_text(answer),
                              ' after %.2f s of sim time' % waited if waited >= ANSWER_NOTED_S else '',
                              ' (and %d other command%s meanwhile)' % (others, '' if others == 1 else 's')
                              if others > 0 else ''))
        if own is None:
            kind = 'is ball_chaser/DriveToTarget (the course\'s md5)'
        else:
            kind = ('is the submission\'s own %s, which takes the course\'s request (%s) and answers '
                    'with %s (%s): judged by what it does'
                    % (own.type_name, service_type.fields_text(own.request),
                       service_type.fields_text(own.response), own.source))
        self.grade.set('drive_bot_service', True, '%s %s; with sim time running: %s'
                       % (submission.COURSE_SERVICE, kind, '; '.join(results)))

    # -- stops_without_ball -------------------------------------------------------------------
    def check_stop(self):
        if not self.world_up():
            self.grade.set('stops_without_ball', False, 'not run: the world did not launch')
            return
        if not self.found.placements_drawn or not self.alive():
            self.grade.set('stops_without_ball', False, 'not run: no placement, or the world ended')
            return
        sim = chase_graph.SimControl()
        placement = self.found.placements_drawn[0]
        self.tracking = trials.RollingLog(STATES_KEPT)
        self.moves.begin()
        start = self.start_placement(sim, placement)
        seen = len(self.cmd)
        robot_start = (placement.robot_x, placement.robot_y, placement.robot_yaw)
        ball_start = (placement.ball_x, placement.ball_y)

        def since_placed():
            """The robot's states from the placement's first on (until one shows it, those
            that came after the reset by the clock, as in a trial)."""
            rows = self.tracking.since(0)
            first = trials.placed_row(rows, robot_start, ball_start)
            return rows[first:] if first is not None else [row for row in rows if row[0] > start]
        # Let the robot set off toward the ball, by its pose: what the grader hears on /cmd_vel
        # is stamped with its own /clock, which lockstep can run a frame ahead of the
        # simulator's, so a "move" and its "stop" may look a frame apart.
        deadline = time.monotonic() + SET_OFF_WALL_S
        while (self.alive() and time.monotonic() < deadline and self.clock.now() - start < 5.0
               and not trials.set_off(since_placed())):
            time.sleep(0.02)
        self.clock.wait(0.5, self.alive)
        sent = self.cmd.since(seen)
        commanded = trials.moving(sent, STILL_SPEED)
        placed = since_placed()
        if not trials.set_off(placed):
            sim.pause()
            self.tracking = None
            path, turned = trials.path_and_turn(placed)
            # Stopping was not seen; not moving toward the ball is the chase's to judge.
            self.grade.not_judged('stops_without_ball',
                                  'with the ball %.1f m ahead the robot did not set off toward it in 5 s '
                                  'of sim time: it travelled %.2f m and turned %.2f rad (motion is %g m '
                                  'or %g rad), %s, so stopping cannot be shown'
                                  % (placement.ball_distance, path, turned, trials.NO_MOTION_M,
                                     trials.NO_MOTION_RAD,
                                     'though it was sent %d motion command%s'
                                     % (len(commanded), '' if len(commanded) == 1 else 's')
                                     if commanded else 'and it was never commanded to move'),
                                  self.excerpt(self.chaser_log))
            return
        hidden_at = self.clock.now()
        sim.delete(self.found.ball)
        self.clock.wait(REACT_S + WATCH_S, self.alive)
        ended_at = self.clock.now()
        sim.pause()
        tracked, self.tracking = self.tracking, None
        if self.counter is not None:
            self.counter.forwarding = False
        poses = [row[:4] for row in tracked.since(0) if row[0] >= hidden_at]
        window = hidden_at + REACT_S
        verdict = trials.judge_stop(self.cmd.since(seen), poses, window, STILL_SPEED,
                                    STILL_DISTANCE_M, STILL_TURN_RAD)
        tampering = self.guard.tampering()
        if tampering:
            self.grade.set('stops_without_ball', False, tampered(tampering))
            return
        foreign = self.moves.end()
        if foreign:
            self.grade.set('stops_without_ball', False, moved(foreign, None, self.found.robot))
            return
        if verdict.poses < 2:
            self.grade.not_judged('stops_without_ball', 'the robot\'s pose could not be read over '
                                  'the %g s after the ball was taken away' % (ended_at - window))
            return
        text = 'the robot was driving toward the ball'
        driving = trials.moving(trials.in_effect(sent), STILL_SPEED) or commanded
        if driving:
            text += ' (command %.2f m/s, %.2f rad/s)' % driving[-1][1:]
        text += ('; the ball was taken away %.1f s after the start; after %g s to react, over the next '
                 '%.1f s the robot travelled %.2f m and turned %.2f rad along its path'
                 % (hidden_at - start, REACT_S, ended_at - window, verdict.path_m, verdict.turned_rad))
        if verdict.moving_commands:
            text += ('; %d motion command%s in effect then, the first (%.2f, %.2f)'
                     % (verdict.moving_commands, '' if verdict.moving_commands == 1 else 's',
                        verdict.first_moving[1], verdict.first_moving[2]))
        else:
            text += '; every command in effect then was a stop'
        if verdict.last_command is not None:
            text += ', the last (%.2f, %.2f)' % verdict.last_command[1:]
        self.grade.set('stops_without_ball', verdict.still, text)

    # -- process_image_calls ------------------------------------------------------------------
    def check_process_image(self):
        if self.found.nodes_before is None:
            return
        chaser_nodes = self.chaser_nodes
        _pubs, subscribers, _services = self.master.getSystemState()
        camera_nodes = sorted({node for topic, nodes in subscribers if topic == CAMERA_TOPIC
                               for node in nodes if node in chaser_nodes})
        if not camera_nodes:
            self.grade.set('process_image_calls', False,
                           'no node of ball_chaser.launch subscribes to %s (its nodes: %s)'
                           % (CAMERA_TOPIC, ', '.join(chaser_nodes) or 'none'),
                           self.excerpt(self.chaser_log))
            return
        if self.counter is None:
            self.grade.not_judged('process_image_calls',
                                  '%s subscribes to %s, but the submission\'s DriveToTarget is not '
                                  'the course\'s, so its calls could not be counted'
                                  % (', '.join(camera_nodes), CAMERA_TOPIC))
            return
        calls = self.counter.calls
        # The extra worlds' calls came during their trials.
        total = len(calls) + self.found.extra_world_calls
        unseen = no_trial_ran(self.grade)
        if not total and unseen:
            # The node was never shown the ball: its silence says nothing of it.
            self.grade.not_judged('process_image_calls',
                                  'no chase trial ran, so %s never saw the ball (%s)'
                                  % (', '.join(camera_nodes), unseen))
            return
        if not total:
            self.grade.set('process_image_calls', False,
                           '%s subscribes to %s but never called %s'
                           % (', '.join(camera_nodes), CAMERA_TOPIC, submission.COURSE_SERVICE),
                           self.excerpt(self.chaser_log))
            return
        kept = calls.since(0)
        first = ', first with linear_x %.2f, angular_z %.2f' % kept[0][1:] if kept else ''
        self.grade.set('process_image_calls', True,
                       '%s subscribes to %s and called %s %d times (%d during the chase trials)%s'
                       % (', '.join(camera_nodes), CAMERA_TOPIC, submission.COURSE_SERVICE,
                          total, self.found.trial_calls, first))


def no_trial_ran(grade):
    """Why no chase trial ran (the chase item's first line, or each trial's error), or '' when
    one did."""
    if any(not trial.error for trial in grade.trials):
        return ''
    if grade.trials:
        return '; '.join('trial %d: %s' % (trial.index, trial.error) for trial in grade.trials)
    chase = grade.item('chase')
    return 'chase: %s' % chase.evidence.split('\n', 1)[0] if chase is not None else 'chase: no result'
