"""The calls to a service, as the node that serves it logs them, for the chase view.

A ROS 1 service call goes straight from the caller to the server; the master
only tells the caller where the server is. So the chase view shows the calls
to /ball_chaser/command_robot through the serving node's log: while a view is
open, ServiceWatch looks up every REFRESH seconds which node serves the
service, keeps that node's lines on /rosout (a chase.LineLog), and raises
its loggers to DEBUG (at each look, for loggers made since) through the node's own set_logger_level service
(chase.loggers_to_raise), remembering their levels; when the last view
closes, or the simulator stops, it puts them back and stops listening.
Everything that talks to other nodes runs on the watch's own thread, each
call within the graph's deadline; a failure only means fewer lines (a node
that cannot be asked keeps its levels), and is shown nowhere as an error.

The graph is what the watch asks of ROS (flatsim.ros.service_watch.RosGraph):
    serving(service) -> (node, uri) or None     who serves it now
    loggers(node) -> [(name, level)]            its ~get_loggers
    set_logger_level(node, logger, level)       its ~set_logger_level
    listen(on_line) -> handle with stop()       /rosout: on_line(node, level, text, stamp)
Each raises on failure or when its deadline passes.

No ROS here.
"""
import threading

from flatsim.studio.chase import COMMAND_WINDOW, LineLog, LoggedLine, ServiceCalls, line_time, loggers_to_raise

COMMAND_SERVICE = '/ball_chaser/command_robot'
# Seconds of wall time between two look-ups of the serving node while a view is open: a
# chaser started (or restarted) after the view opened shows within this.
REFRESH = 2.0


class ServiceWatch:
    def __init__(self, graph, clock, service=COMMAND_SERVICE, window=COMMAND_WINDOW,
                 refresh=REFRESH):
        """clock() is the simulator's sim time now."""
        self.graph = graph
        self.clock = clock
        self.service = service
        self.refresh = refresh
        self.log = LineLog(window)
        self.window = window
        self.server = None            # (node, uri) serving the service, as last looked up
        self.looked_up = False
        self.raised = {}              # logger -> its level before, on self.server's node
        self.listening = None         # the /rosout subscription while open
        self.wanted = False
        self.stopped = False
        self.changed = threading.Condition()
        self.busy = threading.Lock()  # one thread at a time talks to the graph
        self.thread = None

    # -- from the studio -------------------------------------------------------------------
    def open(self):
        """Watch (from now until close()); returns at once."""
        with self.changed:
            if self.stopped:
                return
            self.wanted = True
            if self.thread is None:
                self.thread = threading.Thread(target=self._run, name='service watch', daemon=True)
                self.thread.start()
            self.changed.notify_all()

    def close(self):
        """Stop watching and put the node's levels back, on the watch's thread; returns at once."""
        with self.changed:
            self.wanted = False
            self.changed.notify_all()

    def shutdown(self):
        """The simulator stops: put the levels back now, in this thread, and watch no more."""
        with self.changed:
            self.stopped = True
            self.wanted = False
            self.changed.notify_all()
        with self.busy:
            self._let_go()

    def calls(self, now):
        """ServiceCalls: the serving node and the lines it logged up to sim time now."""
        server = self.server
        node = server[0] if server else None
        lines = self.log.recent(node, now) if node else []
        return ServiceCalls(self.service, node, self.looked_up, tuple(lines))

    # -- from the /rosout subscriber ---------------------------------------------------------
    def on_line(self, node, level, text, stamp):
        server = self.server
        if server is None or node != server[0]:
            return
        at = line_time(stamp, self.clock(), self.window)
        if at is not None:
            self.log.add(LoggedLine(at, node, level, text))

    # -- the watch's thread ------------------------------------------------------------------
    def _run(self):
        while True:
            with self.changed:
                if self.stopped:
                    return
                wanted = self.wanted
            with self.busy:
                if self.stopped:
                    return
                if wanted:
                    self._look()
                else:
                    self._let_go()
            with self.changed:
                if self.wanted == wanted and not self.stopped:
                    # Open: look again in a while; closed: sleep until opened.
                    self.changed.wait(self.refresh if wanted else None)

    def _look(self):
        if self.listening is None:
            try:
                self.listening = self.graph.listen(self.on_line)
            except Exception:  # noqa: BLE001 - no /rosout: no lines, and the next look tries again
                pass
        try:
            server = self.graph.serving(self.service)
        except Exception:  # noqa: BLE001 - the master did not answer: as it was
            return
        self.looked_up = True
        if server != self.server:
            # Another node serves it, or the same name again from a new process (a new
            # address): the old one's levels go back if it is still there, the new one's go up.
            self._restore()
            self.log.clear()
            self.server = server
        if server is not None:
            # Each look: roscpp makes a logger when its first line is logged, and a level may
            # have been put back by hand meanwhile.
            self._raise(server[0])

    def _raise(self, node):
        try:
            loggers = self.graph.loggers(node)
        except Exception:  # noqa: BLE001 - a node that cannot be asked keeps its levels
            return
        for name, level in loggers_to_raise(loggers):
            try:
                self.graph.set_logger_level(node, name, 'DEBUG')
            except Exception:  # noqa: BLE001
                continue
            # The level it had before the watch first raised it is the one to put back.
            self.raised.setdefault(name, level)

    def _restore(self):
        if self.server is not None:
            for name, level in self.raised.items():
                try:
                    self.graph.set_logger_level(self.server[0], name, level)
                except Exception:  # noqa: BLE001 - gone, or not answering: nothing to put back
                    pass
        self.raised = {}

    def _let_go(self):
        if self.listening is not None:
            try:
                self.listening.stop()
            except Exception:  # noqa: BLE001
                pass
            self.listening = None
        self._restore()
        self.server = None
        self.looked_up = False
        self.log.clear()
