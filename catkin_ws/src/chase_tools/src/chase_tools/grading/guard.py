"""What keeps a chase honest: only the grader's own simulator counts (SimulatorGuard), and a
model moved as no chase moves it voids the trial (ModelMoves, moved).
"""
import json
import threading
import time

import rosgraph
import rospy
from std_msgs.msg import String

from chase_tools import chase_graph
from chase_tools.grading import probe, trials
from chase_tools.grading.bounds import NODE_ANSWER_S, POLL_S
from chase_tools.procs import wait_until


# How a trial or an item judged on a simulator that another node impersonated begins its error.
TAMPERED = 'not judged: the simulator was impersonated'
TAMPERING_SHOWN = 3             # of what the guard found, what a verdict quotes
# How a trial or an item begins its error when a model moved in a way no chase moves it: through
# the simulator's API by another node than the grader (flatsim's ~model_moves), or the robot
# faster than it could drive (trials.first_jump).
MOVED = 'not judged: the models were moved during the trial'
MOVES_SHOWN = 3
MOVES_KEPT = 100                # of the moves of one trial, what the grader keeps
# Wall seconds the grader waits for flatsim to say it made the grader's own placements.
MOVES_SEEN_S = 2.0
# Wall seconds between the guard's looks for the simulator at the master, while none is known.
LOOKUP_EVERY_S = 0.5


GUARDS = {}                     # topic -> the SimulatorGuard its messages pass
SERVICE_GUARDS = {}             # service prefix -> the SimulatorGuard that says where to call


def guard_topics(topics, guard):
    """From now on, the messages of these topics reach this process's callbacks only through
    guard.receive. rospy hands each new connection the subscriber's receive_callback as it is
    when the connection is made, which can be before a Subscriber's constructor returns: so
    the class's own is replaced, once, before any subscription."""
    from rospy.topics import _SubscriberImpl
    if not hasattr(_SubscriberImpl, 'unguarded_receive_callback'):
        _SubscriberImpl.unguarded_receive_callback = _SubscriberImpl.receive_callback

        def receive_callback(impl, msgs, connection):
            deliver = impl.unguarded_receive_callback
            guard = GUARDS.get(impl.resolved_name)
            if guard is None:
                deliver(msgs, connection)
            else:
                guard.receive(impl.resolved_name, deliver, msgs, connection)
        _SubscriberImpl.receive_callback = receive_callback
    for topic in topics:
        GUARDS[topic] = guard


def guard_services(prefixes, guard):
    """From now on, this process calls the services under these prefixes where guard.address_for
    says. rospy asks the master at each call, and the master answers with whoever registered
    the name last, which may have given it back by the time anyone looks."""
    from rospy.impl.tcpros_service import ServiceProxy
    if not hasattr(ServiceProxy, 'unguarded_service_uri'):
        ServiceProxy.unguarded_service_uri = ServiceProxy._get_service_uri

        def service_uri(proxy, request):
            guard = next((guard for prefix, guard in SERVICE_GUARDS.items()
                          if proxy.resolved_name.startswith(prefix)), None)
            try:
                given = proxy.unguarded_service_uri(request)
            except rospy.ServiceException:
                # Nobody serves it now: a node that took the name over and then let it go.
                given = None
            return given if guard is None else guard.address_for(proxy.resolved_name, given)
        ServiceProxy._get_service_uri = service_uri
    for prefix in prefixes:
        SERVICE_GUARDS[prefix] = guard


def tampered(found):
    """The error of a verdict that SimulatorGuard.tampering() found reasons not to trust."""
    return '%s: %s' % (TAMPERED, '; '.join(found[:TAMPERING_SHOWN]))


class SimulatorGuard:
    """The model states and sim time count only from the simulator the grader started.

    Any node of the submission can publish on /gazebo/model_states or /clock, or
    serve /gazebo/set_model_state, and so fake a chase. The grader takes messages
    on those topics only over its connection to the simulator node
    (/flatsim), whose address the master gave when the world came up (pin()):
    each connection's endpoint is the publisher address this node connected to,
    which a publisher cannot choose by what it writes in its header. Messages from
    anywhere else are dropped and counted, and tampering() names them, with any
    other publisher of those topics and any service of the simulator's that
    another node took over, before a chase or a stop is judged. The master takes
    any caller's word for its name, so a service the simulator served when the
    world came up must also still be served from the address it had then; and the
    grader calls it there, whatever the master says at the time of a call.
    """
    SIMULATOR = '/flatsim'
    MOVES_TOPIC = SIMULATOR + '/model_moves'
    TOPICS = (chase_graph.MODEL_STATES_TOPIC, chase_graph.SIM_NAMESPACE + '/link_states', '/clock',
              MOVES_TOPIC)
    # Names only a simulator registers under: flatsim's, and gzserver's in Gazebo.
    NAMES = (SIMULATOR, chase_graph.SIM_NAMESPACE)
    SERVICE_PREFIXES = (chase_graph.SIM_NAMESPACE + '/', SIMULATOR + '/')

    def __init__(self, master):
        self.master = master
        self.uri = None
        self.pinned = False
        self.services = {}              # the simulator's services, pinned: name -> address
        self.looked = 0.0
        # (topic, publisher's name) -> [messages dropped, its addresses]: a node started afresh
        # for each trial sends from a new address each time.
        self.refused = {}
        # (service, address) the master gave at a call, not pinned -> the node there then
        self.redirected = {}
        self.claims = []                # nodes a launch of the submission names as the simulator
        self.seen = []                  # what tampering() found before the nodes were stopped
        self.lock = threading.Lock()
        guard_topics(self.TOPICS, self)
        guard_services(self.SERVICE_PREFIXES, self)

    def receive(self, topic, deliver, msgs, connection):
        if connection.endpoint_id == self.simulator_uri():
            deliver(msgs, connection)
        else:
            self.refuse(topic, connection, len(msgs))

    def simulator_uri(self):
        """The simulator's address: pinned once the world is up, else the master's answer."""
        if self.pinned or self.uri is not None:
            return self.uri
        # Each topic's messages come on a thread of their own: the first to ask looks it up,
        # the others wait for its answer rather than take none for one.
        with self.lock:
            if self.uri is None and time.monotonic() - self.looked >= LOOKUP_EVERY_S:
                self.looked = time.monotonic()
                self.uri = self.lookup()
            return self.uri

    def lookup(self):
        try:
            # A master client of its own: this runs on rospy's receiving threads too, and one
            # client's connection is not to be shared among threads.
            return rosgraph.Master(self.master.caller_id).lookupNode(self.SIMULATOR)
        except Exception:  # noqa: BLE001 - no simulator (yet), or a master that does not answer
            return None

    def pin(self):
        """The simulator is up: from now on its address, and its services', must not change."""
        self.uri, self.pinned = self.lookup(), True
        self.services = self.served_as_simulator()

    def address_for(self, service, given):
        """Where to call one of the simulator's services: where it was when the world came up."""
        pinned = self.services.get(service)
        if pinned is None:
            if given is None:
                raise rospy.ServiceException('service [%s] unavailable' % service)
            return given
        if given is not None and given != pinned:
            with self.lock:
                known = (service, given) in self.redirected
            if not known:
                # Named now: the node may be gone, or started afresh elsewhere, by the end.
                node = self.node_at(given)
                with self.lock:
                    self.redirected[(service, given)] = node
        return pinned

    def served_as_simulator(self):
        """{service: its address} of the services the master lists under the simulator's name."""
        try:
            _publishers, _subscribers, services = self.master.getSystemState()
            return {service: self.master.lookupService(service) for service, nodes in services
                    if service.startswith(self.SERVICE_PREFIXES) and nodes == [self.SIMULATOR]}
        except Exception:  # noqa: BLE001 - a master that no longer answers: the run has ended
            return {}

    def node_at(self, address):
        """The node that takes connections at a service's address: a node's topics and services
        share one port, which it gives for the /rosout that every node publishes."""
        wanted = rospy.core.parse_rosrpc_uri(address)
        try:
            publishers, _subscribers, _services = self.master.getSystemState()
        except Exception:  # noqa: BLE001 - a master that no longer answers: the run has ended
            return 'an unknown node'
        for node in dict(publishers).get('/rosout', []):
            try:
                node_api = probe.node_proxy(self.master.lookupNode(node), NODE_ANSWER_S)
                _code, _text, protocol = node_api.requestTopic(self.master.caller_id, '/rosout',
                                                               [['TCPROS']])
                if tuple(protocol[1:3]) == wanted:
                    return node
            except Exception:  # noqa: BLE001 - a node that does not answer is not the one
                continue
        return 'an unknown node'

    def refuse(self, topic, connection, count):
        who = getattr(connection, 'callerid_pub', None) or '?'
        with self.lock:
            dropped = self.refused.setdefault((topic, who), [0, []])
            dropped[0] += count
            if connection.endpoint_id not in dropped[1]:
                dropped[1].append(connection.endpoint_id)

    def keep_what_is_seen(self):
        """Before the submission's nodes are stopped (to start them afresh): what the master
        shows them doing in the simulator's place now, which it forgets with them, stays in
        tampering()."""
        found = self._registered_in_its_place()
        with self.lock:
            self.seen += [line for line in found if line not in self.seen]

    def tampering(self):
        """What another node did in the simulator's place, one line each; [] if nothing."""
        with self.lock:
            found = list(self.claims) + ['%d message%s on %s from %s (%s), which is not the simulator'
                     % (count, '' if count == 1 else 's', topic, who, ', '.join(addresses))
                     for (topic, who), (count, addresses) in sorted(self.refused.items())]
            redirected = sorted(self.redirected.items())
            seen = list(self.seen)
        found += ['at a call of %s the master gave the address of %s (%s), not the simulator\'s'
                  % (service, node, address) for (service, address), node in redirected]
        return found + seen + [line for line in self._registered_in_its_place() if line not in seen]

    def _registered_in_its_place(self):
        """What the master shows other nodes registered as or for the simulator, one line each."""
        found = []
        for name in self.NAMES[1:]:
            try:
                uri = rosgraph.Master(self.master.caller_id).lookupNode(name)
            except Exception:  # noqa: BLE001 - no node of that name
                continue
            found.append('a node registered under the simulator\'s name %s (%s)' % (name, uri))
        try:
            publishers, _subscribers, services = self.master.getSystemState()
        except Exception:  # noqa: BLE001 - a master that no longer answers: the run has ended
            return found
        for topic, nodes in publishers:
            if topic in self.TOPICS:
                found += ['%s publishes on %s, which only the simulator may' % (node, topic)
                          for node in nodes if node != self.SIMULATOR]
        for service, nodes in services:
            if service.startswith(self.SERVICE_PREFIXES):
                found += ['%s serves %s, the simulator\'s service' % (node, service)
                          for node in nodes if node != self.SIMULATOR]
        if self.pinned and self.uri is not None and self.lookup() != self.uri:
            found.append('another node took the simulator\'s name %s (now at %s)'
                         % (self.SIMULATOR, self.lookup()))
        for service, address in sorted(self.served_as_simulator().items()):
            if self.services.get(service, address) != address:
                found.append('%s is served by %s (%s), registered under the simulator\'s name'
                             % (service, self.node_at(address), address))
        # The simulator never gives up a service while it runs: another node that took the
        # name and then ended (or was stopped to start afresh) took the registration with it.
        if self.pinned and self.uri is not None and self.lookup() == self.uri:
            served = {service for service, nodes in services if nodes}
            found += ['%s is no longer registered at the master: a node that took it from the '
                      'simulator ended and took the registration with it' % service
                      for service in sorted(set(self.services) - served)]
        return found


class ModelMoves:
    """The models moved through the simulator's API while a trial runs, as flatsim says on
    ~model_moves (only the simulator's own messages pass the guard)."""

    def __init__(self):
        self.watching = False
        self.moves = []
        self.own = 0                    # the grader's own moves in this watch
        self.own_seen = 0               # the moves flatsim said the grader made in it
        self.lock = threading.Lock()
        rospy.Subscriber(SimulatorGuard.MOVES_TOPIC, String, self.on_move, queue_size=MOVES_KEPT)

    def begin(self):
        with self.lock:
            self.watching, self.moves, self.own, self.own_seen = True, [], 0, 0

    def made(self):
        """The grader moved a model itself."""
        with self.lock:
            self.own += 1

    def on_move(self, msg):
        try:
            said = json.loads(msg.data)
            move = trials.Move(float(said['time']), str(said['by']), str(said['through']),
                               str(said['target']))
        except (ValueError, KeyError, TypeError):
            return
        with self.lock:
            if self.watching:
                self.own_seen += move.by == rospy.get_name()
                if len(self.moves) < MOVES_KEPT:
                    self.moves.append(move)

    def end(self):
        """The moves of this watch that the grader did not make, once flatsim has said the
        grader's own (or MOVES_SEEN_S has passed)."""
        wait_until(lambda: self.own_seen >= self.own, [], MOVES_SEEN_S, poll_s=POLL_S)
        with self.lock:
            self.watching = False
            return trials.moves_not_made_by(self.moves, rospy.get_name(), self.own)


def moved(moves, jump, robot):
    """The error of a trial in which models moved as no chase moves them; '' if none did."""
    found = [move.describe() for move in moves[:MOVES_SHOWN]]
    if len(moves) > MOVES_SHOWN:
        found.append('%d more move%s' % (len(moves) - MOVES_SHOWN,
                                         '' if len(moves) - MOVES_SHOWN == 1 else 's'))
    if jump is not None:
        found.append(jump.describe(robot))
    return '%s: %s' % (MOVED, '; '.join(found)) if found else ''
