"""ball_chaser.launch: started with its clients' calls sent to the counting stand-in, started
again when that guess was wrong, its nodes and services found, and lockstep set up with them."""
import os
import time

import rosgraph
import rospy

from chase_tools import chase_graph
from chase_tools.chase_graph import CAMERA_TOPIC
from chase_tools.grading import probe, service_type, submission
from chase_tools.grading.bounds import CMD_PUBLISHERS_WALL_S, LOCKSTEP_WALL_S, POLL_S
from chase_tools.grading.launches import WorldLaunch, launch_processes
from chase_tools.procs import wait_until


class Chaser:
    """The submission's ball_chaser.launch and its nodes; a part of a world's run."""
    lockstep_on = False             # once enable_lockstep has turned the simulator's lockstep on

    def node_names(self):
        publishers, subscribers, services = self.master.getSystemState()
        return {node for _topic, nodes in publishers + subscribers + services for node in nodes}

    def start_chaser(self):
        # A simulator that is gone (shut down when another node took its name) holds nothing.
        if self.models is not None and self.alive():
            chase_graph.SimControl().pause()
        if not self.spec.chaser_launches_world:
            self.found.nodes_before = self.node_names()
            self.start_chaser_launch()
        self.wait_for_chaser()
        keep = []
        if self.stand_in_taken():
            # The guess of which node is drive_bot was wrong: it serves the stand-in's name.
            server = self.service_provider(submission.PROXY_SERVICE).lstrip('/').split('/')[-1]
            keep.append(server)
            self.grade.notes.append('%s serves %s but was taken for a client; ball_chaser.launch '
                                    'was started again with it left alone'
                                    % (server, submission.COURSE_SERVICE))
            self.restart_chaser(keep)
        headers = self.served_headers()
        served = headers.get('md5sum') if headers is not None else None
        own = self.own_service(headers) if served not in (None, self.counter.srv_type._md5sum) else None
        if isinstance(own, service_type.ServiceDefinition) and service_type.has_course_request(own):
            # Only the response differs: the stand-in serves the submission's own type.
            self.counter.serve_as(service_type.service_class(own))
            self.note_own_response(own)
            self.restart_chaser(keep)
        elif served not in (None, self.counter.srv_type._md5sum):
            self.grade.notes.append(
                '%s is served with md5 %s, not the course\'s DriveToTarget (md5 %s): the grader\'s '
                'counting stand-in cannot forward its calls, so ball_chaser.launch was started '
                'again as written; the chase is judged on its own wiring, and process_image\'s '
                'calls are not counted' % (submission.COURSE_SERVICE, served,
                                           self.counter.srv_type._md5sum))
            self.counter.close()
            self.counter = None
            self.restart_chaser(keep)
        if self.counter is not None and self.found.chaser_changes.remapped:
            self.grade.notes.append('calls to %s counted from %s (remapped to the grader\'s '
                                    'counting stand-in, which forwards them)'
                                    % (submission.COURSE_SERVICE,
                                       ', '.join(self.found.chaser_changes.remapped)))

    def start_chaser_launch(self, keep=()):
        """Start ball_chaser.launch, its clients' calls sent to the stand-in if it runs."""
        chaser_dir = os.path.join(self.spec.overlay_root, 'src', self.spec.chaser_package)
        self.found.chaser_changes = self.prepare_launch_files(
            chaser_dir, remap=self.counter is not None, keep=keep)
        self.launch_chaser()

    def launch_chaser(self):
        """Start ball_chaser.launch as prepared."""
        self.chaser_log_start = os.path.getsize(self.chaser_log) if os.path.exists(self.chaser_log) else 0
        self.start_submission_launch(self.chaser, self.spec.chaser_package, 'ball_chaser.launch',
                                     self.chaser_log)

    def restart_chaser(self, keep):
        self.guard.keep_what_is_seen()
        self.stop_launch(self.chaser, 'ball_chaser.launch')
        if self.counter is not None:
            self.counter.advertise()
        self.start_chaser_launch(keep)
        # When it includes world.launch, the world stays: the simulator is the grader's, and
        # the robot it spawned is still there (a second spawn of it is refused).
        self.wait_for_chaser()

    def start_chaser_afresh(self):
        """ball_chaser.launch stopped and started again with the world held (paused), so that no
        node keeps what it believed before the grader stopped and moved the robot behind its
        back: a node that sends a command only when its decision changes would send none. When
        it includes world.launch, the world stays, as in restart_chaser. Bounded by the waits it
        makes (fresh_start_wall_s); its wall seconds go in the session's log."""
        begun = time.monotonic()
        self.guard.keep_what_is_seen()
        # The nodes to wait for once they are back: drive_bot answers before process_image
        # (which waits for its service) has subscribed to the camera.
        links = self.chaser_links()
        # The simulator keeps its camera's connections to the stopped nodes until a frame
        # fails on them, and the world is paused: they must not pass for the new ones'.
        stale = chase_graph.simulator_links(self.master)
        self.stop_launch(self.chaser, 'ball_chaser.launch')
        stopped = time.monotonic()
        self.launch_chaser()
        self.wait_for_chaser()
        served = time.monotonic()
        self.wait_for_cmd_publishers()
        self.wait_for_links(links, stale={link[0] for link in stale})
        if self.lockstep_on:
            # New nodes answer their first frame cold: lockstep waits for them as for new ones.
            chase_graph.SimControl().set_lockstep(True)
        ended = time.monotonic()
        self.say('ball_chaser.launch started afresh in %.1f s (stopped in %.1f s, its service '
                 'answered %.1f s later, its nodes connected %.1f s after that)'
                 % (ended - begun, stopped - begun, served - stopped, ended - served))

    def wait_for_chaser(self):
        """Until drive_bot's service answers, or ball_chaser.launch's nodes have all died.

        Answers, not only registered: a drive_bot killed with an earlier launch
        stays registered until the new one takes its name.
        """
        deadline = time.monotonic() + self.spec.chaser_timeout
        while time.monotonic() < deadline and self.chaser.alive():
            if self.served_md5() is not None or self.stand_in_taken():
                return
            started, died = launch_processes(self.chaser_log, self.chaser_log_start)
            if started and started <= died:
                return
            time.sleep(POLL_S)

    def served_md5(self):
        """The md5 of the service at the course's name, or None if nothing answers there."""
        headers = self.served_headers()
        return headers.get('md5sum') if headers is not None else None

    def served_headers(self):
        """The header the service at the course's name answers a probe with; None if nothing
        answers there."""
        uri = self.service_uri(submission.COURSE_SERVICE)
        if uri is None:
            return None
        try:
            return probe.service_headers(uri, submission.COURSE_SERVICE)
        except probe.ProbeError:
            return None

    def own_service(self, headers):
        """The submission's definition of the type its service is served with (headers, a
        probe's answer): a service_type.ServiceDefinition read from its .srv as text, or the
        ServiceTypeError why it could not be read. Read once for each md5."""
        md5 = headers.get('md5sum')
        if self.found.own_service is None or self.found.own_service[0] != md5:
            try:
                own = service_type.read_definition(self.spec.overlay_root, self.spec.chaser_package,
                                                   headers.get('type'), md5)
            except service_type.ServiceTypeError as error:
                own = error
            self.found.own_service = (md5, own)
        return self.found.own_service[1]

    def note_own_response(self, own):
        if service_type.response_is_course(own):
            differs = 'the course\'s response, and constants that give it another md5 (%s)' % own.source
        else:
            differs = ('its response is %s where the course\'s is %s (%s)'
                       % (service_type.fields_text(own.response),
                          service_type.fields_text(service_type.COURSE_RESPONSE), own.source))
        note = ('%s takes the course\'s request (%s), and %s: the grader calls it, and serves its '
                'counting stand-in, with the submission\'s own %s, and judges drive_bot_service by '
                'what the service does' % (submission.COURSE_SERVICE,
                                           service_type.fields_text(own.request), differs,
                                           own.type_name))
        if note not in self.grade.notes:
            self.grade.notes.append(note)

    def stand_in_taken(self):
        """True when a node of the submission, not this one, serves the stand-in's name."""
        return self.counter is not None and self.service_provider(submission.PROXY_SERVICE) not in (
            None, rospy.get_name())

    @property
    def chaser_nodes(self):
        """The nodes that came with ball_chaser.launch (and are still registered)."""
        if self.found.nodes_before is None:
            return []
        # The simulator too, when ball_chaser.launch starts the world.
        return sorted(self.node_names() - self.found.nodes_before
                      - {rospy.get_name(), '/' + WorldLaunch.SIMULATOR})

    def service_uri(self, name):
        try:
            return self.master.lookupService(name)
        except rosgraph.masterapi.Error:
            return None

    def service_provider(self, name):
        _pubs, _subs, services = self.master.getSystemState()
        for service, nodes in services:
            if service == name and nodes:
                return nodes[0]
        return None

    def chaser_services(self):
        _pubs, _subs, services = self.master.getSystemState()
        found = []
        for service, nodes in services:
            if set(nodes) & set(self.chaser_nodes) and not service.endswith(
                    ('/get_loggers', '/set_logger_level')):
                try:
                    kind = probe.service_headers(self.master.lookupService(service),
                                                 service).get('type', '?')
                except (probe.ProbeError, rosgraph.masterapi.Error):
                    kind = '?'
                found.append('%s (%s)' % (service, kind))
        return found

    def call_drive_bot(self, srv_type, request, within):
        """drive_bot's answer to request (linear_x, angular_z), within `within` wall seconds in
        all; rospy.ServiceException otherwise."""
        uri = self.service_uri(submission.COURSE_SERVICE)
        if uri is None:
            raise rospy.ServiceException('service [%s] unavailable' % submission.COURSE_SERVICE)
        try:
            return probe.call_service(uri, submission.COURSE_SERVICE, srv_type,
                                      srv_type._request_class(*request), within)
        except probe.ProbeError as error:
            raise rospy.ServiceException(str(error)) from None

    def wait_for_cmd_publishers(self, wall_timeout=CMD_PUBLISHERS_WALL_S):
        """Until this node's /cmd_vel subscriber is connected to every publisher of /cmd_vel."""
        deadline = time.monotonic() + wall_timeout
        while time.monotonic() < deadline:
            publishers, _subs, _services = self.master.getSystemState()
            count = sum(len(nodes) for topic, nodes in publishers if topic == '/cmd_vel')
            if self.cmd_sub.get_num_connections() >= count:
                return
            time.sleep(0.05)

    # -- lockstep ------------------------------------------------------------------------
    def chaser_links(self):
        """(the node of ball_chaser.launch that takes the camera, the one that publishes
        /cmd_vel), as the master has them now; None without both."""
        publishers, subscribers, _services = self.master.getSystemState()
        chaser_nodes = set(self.chaser_nodes)
        camera = [n for t, nodes in subscribers if t == CAMERA_TOPIC for n in nodes if n in chaser_nodes]
        driver = [n for t, nodes in publishers if t == '/cmd_vel' for n in nodes if n in chaser_nodes]
        return (camera[0], driver[0]) if camera and driver else None

    def wait_for_links(self, links=None, stale=frozenset()):
        """Until the simulator is connected to the node that takes the camera and to the one
        that drives, links (chaser_links(), by default as they are now), for LOCKSTEP_WALL_S at
        most: a frame sent before flatsim has connected to the chaser is lost, and under
        lockstep a command from a driver it has not yet connected to arrives unannounced.
        stale: ids of the simulator's connections that do not count."""
        links = links or self.chaser_links()
        if links:
            camera, driver = links
            wait_until(lambda: chase_graph.lockstep_ready(self.master, CAMERA_TOPIC, chaser=camera,
                                                          driver=driver, stale=stale),
                       [], LOCKSTEP_WALL_S, poll_s=0.05)

    def enable_lockstep(self):
        """Sim time waits for the controller after each frame, and otherwise runs as fast as it
        can: the outcome no longer depends on the machine's speed or load."""
        if not self.spec.lockstep:
            self.grade.notes.append('chases in real time (--real-time)')
            return
        if not self.world_up():
            return
        self.wait_for_links()
        sim = chase_graph.SimControl()
        if not sim.set_lockstep(True):
            self.grade.notes.append('the simulator offers no lockstep: chases in real time')
            return
        sim.set_real_time_factor(0.0)
        self.lockstep_on = True
        self.grade.notes.append('chases in lockstep, as fast as the nodes answer')
