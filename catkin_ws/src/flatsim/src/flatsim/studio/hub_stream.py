"""What the hub sends the pages in sight as the world runs: the scene when models come or go,
their poses, the status, the lidars' rays and the camera and chase views. No ROS here."""
import numpy as np

from flatsim.studio import chase
from flatsim.studio.frames import camera_frame, dumps

# The real-time factor is measured over this much wall time, as gzclient averages it.
RTF_WINDOW = 1.0


class HubStream:
    """Hub's stream; Hub (flatsim.studio.hub) sets up the state it uses."""

    # -- the stream ------------------------------------------------------------------
    def tick(self):
        """Send what changed since the last tick. Does nothing while no page is in sight."""
        watching = self._streaming()
        if not watching:
            return
        now = self.clock()
        snapshot = self.snapshot()
        if snapshot.models_key != self.models_key:
            self._new_scene(snapshot)
        self._send_poses(snapshot)
        self._expire_leases(now)
        if now >= self.next_status or snapshot.paused != self.last_snapshot.paused \
                or snapshot.sim_time < self.last_sim_time:
            self.next_status = now + self.status_period
            self.broadcast(self._status(snapshot, now), watching)
        self.last_snapshot = snapshot
        if self.scans_wanted and now >= self.next_scans:
            self.next_scans = now + self.scan_period
            self._send_scans()
        if now >= self.next_camera:
            self.next_camera = now + self.camera_period
            self._send_camera_images()

    def _new_scene(self, snapshot):
        """Models came or went: every page gets the whole scene, then all poses."""
        self.models_key = snapshot.models_key
        self.model_names = set(snapshot.poses)
        scene = self.world.scene()
        self.cameras = {'%s::%s' % (model['name'], sensor['name']) for model in scene['models']
                        for sensor in model['sensors'] if sensor['kind'] == 'camera'}
        self.scene_text = dumps(dict(scene, type='scene'))
        self.skipped_text = dumps({'type': 'skipped', 'items': self.world.skipped()})
        for session in list(self.sessions.values()):
            self.deliver(session, self.scene_text)
            self.deliver(session, self.skipped_text)
            session.needs_full_poses = True
        gone = [model for model in self.leases if model not in self.model_names]
        for model in gone:
            del self.leases[model]
        if gone:
            self.broadcast(self._leases_message())
        if self.last_snapshot is None:
            self.last_snapshot = snapshot

    def _send_poses(self, snapshot):
        """Only the moving models whose rounded pose changed are turned into JSON."""
        sessions = self._streaming()
        full = [s for s in sessions if s.needs_full_poses]
        rest = [s for s in sessions if not s.needs_full_poses]
        rounded = snapshot.rounded_poses
        last = self.last_moving
        if last is None or last[0] != snapshot.moving or last[1].shape != rounded.shape:
            rows = range(len(snapshot.moving))
        else:
            rows = np.flatnonzero((rounded != last[1]).any(axis=1)).tolist()
        self.last_moving = (snapshot.moving, rounded)
        changed = {snapshot.moving[row]: snapshot.moving_pose(row) for row in rows}
        # Static models move only by hand, and then the snapshot's poses are a new dict.
        if snapshot.static_poses is not self.last_static:
            if self.last_static is not None:
                changed.update({name: pose for name, pose in snapshot.static_poses.items()
                                if self.last_static.get(name) != pose})
            self.last_static = snapshot.static_poses
        link_poses = snapshot.link_poses
        links = {name: poses for name, poses in link_poses.items()
                 if self.last_links.get(name) != poses}
        self.last_links = link_poses
        self.last_poses.update(changed)
        sim_time = round(snapshot.sim_time, 6)
        if full:
            self.last_poses = snapshot.poses
            self.broadcast({'type': 'poses', 'full': True, 'sim_time': sim_time,
                            'models': self.last_poses, 'links': link_poses}, full)
            for session in full:
                session.needs_full_poses = False
        if rest and (changed or links):
            self.broadcast({'type': 'poses', 'sim_time': sim_time, 'models': changed,
                            'links': links}, rest)

    def _status(self, snapshot, now):
        if snapshot.sim_time < self.last_sim_time:
            # Time went back (Reset World): real time starts over with it, as in gzclient.
            self.real_time_start = now
            self.rtf_samples = []
        self.last_sim_time = snapshot.sim_time
        self.rtf_samples = [(w, s) for w, s in self.rtf_samples if now - w <= RTF_WINDOW]
        self.rtf_samples.append((now, snapshot.sim_time))
        wall0, sim0 = self.rtf_samples[0]
        rtf = (snapshot.sim_time - sim0) / (now - wall0) if now - wall0 > 0.05 else 0.0
        return {'type': 'status', 'sim_time': round(snapshot.sim_time, 6),
                'real_time': round(now - self.real_time_start, 3),
                'real_time_factor': round(rtf, 3), 'paused': snapshot.paused,
                'iterations': snapshot.iterations, 'step_size': snapshot.step_size}

    def _update_scan_wish(self):
        wanted = any(s.scans for s in self._streaming())
        if wanted != self.scans_wanted:
            self.scans_wanted = wanted
            self.world.want_scans(wanted)

    def _update_command_wish(self):
        """The simulator records the drive commands robots get, and watches the calls to
        /ball_chaser/command_robot, only while a page in sight shows a chase view."""
        wanted = any(s.chase for s in self._streaming())
        if wanted != self.commands_wanted:
            self.commands_wanted = wanted
            self.world.want_commands(wanted)

    def _send_scans(self):
        scans = [vars(scan) for scan in self.world.scans()]
        self.broadcast({'type': 'scans', 'scans': scans},
                       [s for s in self._streaming() if s.scans])

    def _send_camera_images(self):
        """One render per camera that some page shows, in the camera panel or the chase view."""
        wanted = {}
        for session in self._streaming():
            if session.camera:
                wanted.setdefault(session.camera, ([], []))[0].append(session)
            if session.chase:
                wanted.setdefault(session.chase, ([], []))[1].append(session)
        for sensor, (cameras, chases) in wanted.items():
            image = self.world.camera_image(sensor)
            if image is None:
                continue
            sim_time, pixels = image
            if cameras:
                frame = camera_frame(sensor, sim_time, pixels)
                for session in cameras:
                    self.deliver(session, frame)
            if chases:
                commands = self.world.drive_commands(sensor.rpartition('::')[0], sim_time)
                calls = self.world.service_calls(sim_time)
                frame = chase.chase_frame(sensor, sim_time, pixels, commands, calls)
                for session in chases:
                    self.deliver(session, frame)

