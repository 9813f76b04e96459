"""The studio server's stream (the ticker) without a browser or ROS: it goes on through a
page whose transport fails and through a frame that fails, and never sleeps holding the hub."""
import asyncio
import logging
import types

from flatsim.studio import server as studio_server
from flatsim.studio.hub import Hub
from flatsim.studio.server import StudioServer
from flatsim.studio.sim_world import SimWorld

from test_studio_hub import Tab, sim  # noqa: F401 - the fixture


class BrokenTab(Tab):
    """A page whose connection breaks once it is open."""

    def __init__(self):
        super().__init__()
        self.broken = False

    def send_text(self, text):
        if self.broken:
            raise ConnectionResetError('the tab went away')
        super().send_text(text)


def run_ticker(server, until, timeout=10.0):
    """Run the server's ticker on a loop of its own until until() or timeout; returns
    (whether the ticker task was still running, whether the hub's lock was ever seen free
    while it ran)."""
    loop = asyncio.new_event_loop()
    server.loop = loop
    seen_free = []

    async def watch():
        server.wake_ticker = asyncio.Event()
        ticker = asyncio.ensure_future(server._tick_while_open())
        deadline = loop.time() + timeout
        while not until() and loop.time() < deadline:
            if server.hub_lock.acquire(blocking=False):
                server.hub_lock.release()
                seen_free.append(True)
            await asyncio.sleep(0.002)
        running = not ticker.done()
        if ticker.done():
            ticker.result()        # a ticker that died shows why
        ticker.cancel()
        return running
    try:
        return loop.run_until_complete(watch()), bool(seen_free)
    finally:
        loop.close()


def test_the_stream_goes_on_past_a_page_whose_send_raises(sim, caplog):
    hub = Hub(SimWorld(sim), stream_rate=200.0, status_rate=100.0)
    server = StudioServer(hub, '', '')
    good, bad = Tab(), BrokenTab()
    hub.connect(good)
    hub.connect(bad)
    bad.broken = True
    before = len(good.of_type('status'))
    with caplog.at_level(logging.ERROR, logger='flatsim.studio'):
        running, _ = run_ticker(server, lambda: len(good.of_type('status')) >= before + 5)
    assert running
    assert len(good.of_type('status')) >= before + 5
    # The broken page is named once, not at every frame.
    assert caplog.text.count('window 2: a message could not be sent') == 1


class FailingHub:
    """A hub whose first frames fail."""
    stream_rate = 200.0
    active = watched = True

    def __init__(self, failures):
        self.failures = failures
        self.ticks = 0
        self.log = logging.getLogger('flatsim.studio')

    def tick(self):
        self.ticks += 1
        if self.ticks <= self.failures:
            raise RuntimeError('a frame went wrong')


def test_the_ticker_survives_failing_frames_and_never_sleeps_holding_the_hub(monkeypatch, caplog):
    monkeypatch.setattr(studio_server, 'TICK_BACKOFF', 0.05)
    hub = FailingHub(failures=2)
    server = StudioServer(hub, '', '')
    with caplog.at_level(logging.ERROR, logger='flatsim.studio'):
        running, seen_free = run_ticker(server, lambda: hub.ticks >= 5)
    assert running and hub.ticks >= 5
    assert caplog.text.count('the stream failed') == 2
    # While it waits after a failed frame, a request may take the hub.
    assert seen_free
    assert not server.hub_lock.locked()


def test_the_ticker_ends_when_the_last_page_closes():
    hub = FailingHub(failures=0)
    hub.active = False
    server = StudioServer(hub, '', '')
    running, _ = run_ticker(server, lambda: False, timeout=0.2)
    assert not running and hub.ticks == 0


def test_a_page_through_a_forwarded_port_is_its_own_but_a_named_site_never_is(sim):  # noqa: F811
    server = StudioServer(Hub(SimWorld(sim)), '', '', host='0.0.0.0')
    server.port = 8080

    def own(origin, host):
        return server._own_origin(types.SimpleNamespace(headers={'Origin': origin}, host=host))

    assert server.url.startswith('http://127.0.0.1:8080/?token=')
    assert own('http://127.0.0.1:8080', '127.0.0.1:8080')
    # ssh -L 9090:127.0.0.1:8080, docker run -p 9090:8080, or the lab server's own address.
    assert own('http://localhost:9090', 'localhost:9090')
    assert own('http://10.0.0.5:8080', '10.0.0.5:8080')
    assert own('http://[::1]:9090', '[::1]:9090')
    # Another site's page, even one whose name its DNS points here.
    assert not own('http://example.org', '10.0.0.5:8080')
    assert not own('http://studio.example:8080', 'studio.example:8080')
    assert not own('', '10.0.0.5:8080')
