"""The studio's HTTP and WebSocket server: a thin aiohttp layer over flatsim.studio.hub.

It runs in a thread of its own with its own asyncio loop, and listens on
127.0.0.1 unless told another address (listen_address(): `gazebo --listen`, the
simulator's ~studio_listen), for a browser on another machine or outside a
container; it warns then. Every request needs the per-run token, given in the address
(?token=...) or as the first part of its path (/s/TOKEN/static/..., where the
page loads its own modules from); anything else gets 403. No cookie holds it:
a browser sends a cookie of 127.0.0.1 to every server there, whatever its
port, and so to any other user's local page. A WebSocket must also come
from a page of this server (its Origin), so that another site cannot drive
the simulator from a user's browser. A page reached through a forwarded port
(`ssh -L`, `docker run -p`) has the origin of the address the browser used, which
the request's Host names.

Routes: / (the page, client/index.html), /static/ (the page's modules),
/three/ (three.js, as npm installed it), /ws (the protocol, one socket per tab).

The page can be served before the world is ready to be shown (the simulator
starts the studio first, so that the browser loads the page while the world
loads): start(world_open=False), then open_world(); a tab's WebSocket waits
for that before the hub greets it.

Requests run on one worker thread, in order, so that the loop never waits for
a change to the simulator; the stream runs in the loop's thread. One lock keeps
the two out of the hub at the same time. While no tab is open, or none is in
sight, nothing runs.
"""
import asyncio
import collections
import concurrent.futures
import hmac
import ipaddress
import os
import secrets
import threading
import urllib.parse

from aiohttp import WSMsgType, web

from flatsim.errors import FlatsimError
from flatsim.studio import address
from flatsim.studio.protocol import MAX_REQUEST_BYTES

HOST = address.LOOPBACK
# Addresses that mean every interface: the page's own address is then given on loopback.
ANY_ADDRESS = ('0.0.0.0', '::')
# A tab that falls this many messages behind is closed rather than buffered without end.
MAX_PENDING = 2000
# A request over the hub's limit (flatsim.studio.protocol.MAX_REQUEST_BYTES) still reaches the
# hub, which tells the page so; only one far beyond it closes the socket unread.
MAX_FRAME_BYTES = 4 * MAX_REQUEST_BYTES
START_TIMEOUT = 10.0
# After a frame that failed, the stream waits this long (s) before the next, so that a
# failure on every frame does not flood the log.
TICK_BACKOFF = 1.0


class StudioError(FlatsimError):
    """The studio could not start."""


def port_number(value):
    """The ~studio_port parameter as a TCP port (0: any free one); StudioError if it is none."""
    if isinstance(value, str) and value.strip().isdigit():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 65535:
        raise StudioError('~studio_port must be a whole number from 0 (any free port) to 65535, '
                          'got %.40r' % (value,))
    return value


def listen_address(value):
    """The ~studio_listen parameter as an IP address to listen on; StudioError if it is none."""
    try:
        return address.listen_address(value)
    except ValueError as error:
        raise StudioError(str(error)) from None


def _address_host(host):
    """Whether a Host header names an IP address or localhost (any port)."""
    try:
        name = urllib.parse.urlsplit('http://' + host).hostname or ''
    except ValueError:
        return False
    if name == 'localhost':
        return True
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


class _Transport:
    """A session's outgoing messages: queued from the hub's thread, written by the loop."""

    def __init__(self, loop, socket):
        self.loop = loop
        self.loop_thread = threading.get_ident()     # made in the loop's own thread
        self.socket = socket
        self.pending = collections.deque()
        self.ready = asyncio.Event()
        self.overflowed = False

    def send_text(self, text):
        self._from_any_thread(text)

    def send_bytes(self, data):
        self._from_any_thread(bytes(data))

    def _from_any_thread(self, item):
        if threading.get_ident() == self.loop_thread:
            self._put(item)
        else:
            self.loop.call_soon_threadsafe(self._put, item)

    def _put(self, item):
        if len(self.pending) >= MAX_PENDING:
            self.overflowed = True
        else:
            self.pending.append(item)
        self.ready.set()

    async def pump(self):
        try:
            while not self.socket.closed:
                await self.ready.wait()
                self.ready.clear()
                if self.overflowed:
                    await self.socket.close(message=b'the page fell too far behind the simulator')
                    return
                while self.pending and not self.socket.closed:
                    item = self.pending.popleft()
                    if isinstance(item, str):
                        await self.socket.send_str(item)
                    else:
                        await self.socket.send_bytes(item)
        except (ConnectionError, RuntimeError):
            return  # the tab went away mid-message; its handler sees the socket close


class StudioServer:
    """Serve a hub and the page on host:port (0: any free port); host 127.0.0.1 unless given."""

    def __init__(self, hub, client_dir, three_dir, port=0, token=None, log=None, host=HOST):
        self.hub = hub
        self.host = listen_address(host)
        self.client_dir = client_dir
        self.three_dir = three_dir
        self.requested_port = port_number(port)
        self.token = token or secrets.token_urlsafe(32)
        self.log = log or hub.log
        self.port = None
        self.loop = None
        self.runner = None
        self.thread = None
        self.worker = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix='flatsim-studio')
        self.hub_lock = threading.Lock()
        self.ticker = None
        self.wake_ticker = None       # set when a request may have put a tab back in sight
        self.world_opened = None      # set when pages may be shown the world
        self._open_at_start = True
        self.sockets = set()
        self._started = threading.Event()
        self._start_error = None

    @property
    def url(self):
        return 'http://%s:%d/?token=%s' % (self.page_host, self.port, self.token)

    @property
    def page_host(self):
        """The host in the page's address: loopback when listening on every address."""
        if self.host in ANY_ADDRESS:
            return HOST
        return '[%s]' % self.host if ':' in self.host else self.host

    @property
    def asset_prefix(self):
        """Where the page's modules are served: a path only this studio's page knows."""
        return '/s/%s' % self.token

    # -- life ------------------------------------------------------------------------
    def start(self, world_open=True):
        """Listen, serving from a thread of its own; returns the page's address.

        world_open=False: serve the page, but greet its WebSocket only after open_world().
        """
        self._open_at_start = world_open
        for folder, what in ((self.client_dir, 'the page'), (self.three_dir, 'three.js')):
            if not os.path.isdir(folder):
                raise StudioError('%s is missing: %s (run ./setup.sh)' % (what, folder))
        self.thread = threading.Thread(target=self._serve, name='flatsim-studio-loop', daemon=True)
        self.thread.start()
        if not self._started.wait(START_TIMEOUT):
            raise StudioError('the studio did not start within %g s' % START_TIMEOUT)
        if self._start_error is not None:
            raise StudioError('the studio cannot listen on %s port %d: %s'
                              % (self.host, self.requested_port, self._start_error))
        if not address.is_loopback(self.host):
            self.log.warning('studio: %s', address.exposed_warning(self.host, self.port))
        return self.url

    def open_world(self):
        """The world is ready: pages waiting for it are shown it now."""
        self.loop.call_soon_threadsafe(self.world_opened.set)

    def stop(self, timeout=5.0):
        if self.loop is not None and self.loop.is_running():
            asyncio.run_coroutine_threadsafe(self._shutdown(), self.loop)
        if self.thread is not None:
            self.thread.join(timeout)
        self.worker.shutdown(wait=False)

    def _serve(self):
        self.loop = asyncio.new_event_loop()
        asyncio.set_event_loop(self.loop)
        self.wake_ticker = asyncio.Event()
        self.world_opened = asyncio.Event()
        if self._open_at_start:
            self.world_opened.set()
        try:
            self.loop.run_until_complete(self._listen())
        except OSError as error:
            self._start_error = error
            self._started.set()
            self.loop.close()
            return
        self._started.set()
        try:
            self.loop.run_forever()
        finally:
            self.loop.close()

    async def _listen(self):
        app = web.Application(middlewares=[self._guard], client_max_size=MAX_REQUEST_BYTES)
        app.router.add_get('/', self._index)
        app.router.add_get('/ws', self._websocket)
        for prefix in ('', self.asset_prefix):
            app.router.add_static(prefix + '/static/', self.client_dir, follow_symlinks=False)
            app.router.add_static(prefix + '/three/', self.three_dir, follow_symlinks=False)
        self.runner = web.AppRunner(app, access_log=None, handle_signals=False)
        await self.runner.setup()
        site = web.TCPSite(self.runner, self.host, self.requested_port, reuse_address=False)
        try:
            await site.start()
        except OSError:
            await self.runner.cleanup()
            raise
        self.port = self.runner.addresses[0][1]

    async def _shutdown(self):
        for socket in list(self.sockets):
            await socket.close(message=b'the simulator stopped')
        await self.runner.cleanup()
        self.loop.stop()

    # -- guard -----------------------------------------------------------------------
    def _token_ok(self, request):
        given = request.query.get('token') or ''
        if not given and request.path.startswith('/s/'):
            given = request.path.split('/')[2]
        return hmac.compare_digest(given.encode(), self.token.encode())

    def _own_origin(self, request):
        origin = request.headers.get('Origin', '')
        if origin in ('http://%s:%d' % (HOST, self.port), 'http://localhost:%d' % self.port):
            return True
        # The address the browser reached the page by, through a forwarded port (ssh -L,
        # docker run -p): an IP address or localhost, never a name that another site's DNS
        # could point here (a page of that site would have that name as its origin and Host).
        return origin == 'http://%s' % request.host and _address_host(request.host)

    @web.middleware
    async def _guard(self, request, handler):
        if not self._token_ok(request):
            return web.Response(status=403, text='403: this page needs the address with its token, '
                                                 'as gzclient prints it\n')
        response = await handler(request)
        # The token is in the address: never hand it to another site, nor be framed by one.
        response.headers['Referrer-Policy'] = 'no-referrer'
        response.headers['X-Frame-Options'] = 'DENY'
        response.headers['X-Content-Type-Options'] = 'nosniff'
        return response

    # -- routes ----------------------------------------------------------------------
    async def _index(self, request):
        """The page, its modules' addresses under asset_prefix."""
        with open(os.path.join(self.client_dir, 'index.html'), encoding='utf-8') as stream:
            page = stream.read()
        for folder in ('static', 'three'):
            page = page.replace('"/%s/' % folder, '"%s/%s/' % (self.asset_prefix, folder))
        return web.Response(text=page, content_type='text/html', charset='utf-8',
                            headers={'Cache-Control': 'no-store'})

    async def _websocket(self, request):
        if not self._own_origin(request):
            self.log.warning('studio: refused a WebSocket from origin %r',
                             request.headers.get('Origin'))
            return web.Response(status=403, text='403: not from this studio\'s own page\n')
        # Uncompressed: on loopback, deflating every pose message would cost the
        # simulator's process CPU and save nothing.
        socket = web.WebSocketResponse(heartbeat=10.0, max_msg_size=MAX_FRAME_BYTES,
                                       compress=False)
        await socket.prepare(request)
        self.sockets.add(socket)
        transport = _Transport(self.loop, socket)
        pump = asyncio.ensure_future(transport.pump())
        await self.world_opened.wait()
        try:
            session = await self._run(self.hub.connect, transport)
        except Exception as error:  # noqa: BLE001 - this tab fails, the studio stays
            self.log.error('studio: a page could not be shown the world: %r', error, exc_info=True)
            self.sockets.discard(socket)
            pump.cancel()
            await socket.close(message=b'the studio could not read the world')
            return socket
        self._ensure_ticker()
        try:
            async for message in socket:
                if message.type == WSMsgType.TEXT:
                    await self._run(self.hub.receive, session, message.data)
                elif message.type == WSMsgType.BINARY:
                    await self._run(self.hub.receive, session, '(a binary frame)')
                self.wake_ticker.set()
        finally:
            self.sockets.discard(socket)
            await self._run(self.hub.disconnect, session)
            self.wake_ticker.set()
            pump.cancel()
        return socket

    # -- the hub's thread ------------------------------------------------------------
    def _run(self, function, *args):
        return self.loop.run_in_executor(self.worker, self._locked, function, *args)

    def _locked(self, function, *args):
        with self.hub_lock:
            return function(*args)

    def _ensure_ticker(self):
        self.wake_ticker.set()
        if self.ticker is None or self.ticker.done():
            self.ticker = asyncio.ensure_future(self._tick_while_open())

    async def _tick_while_open(self):
        """The stream, in the loop's own thread: a hop to another thread per frame would cost
        the simulator more than the frame. A frame is skipped while a request holds the hub
        (a pause can wait up to a second for lockstep to settle). Nothing here sleeps holding
        the hub, and a frame that fails is logged and the stream goes on: a page must never
        freeze because one frame went wrong."""
        period = 1.0 / self.hub.stream_rate
        while True:
            started = self.loop.time()
            state = self._tick_once()
            if state == 'closed':
                return
            if state == 'hidden':
                # No await since the check: a request's wake cannot fall in between.
                self.wake_ticker.clear()
                await self.wake_ticker.wait()
                continue
            pause = TICK_BACKOFF if state == 'failed' else period - (self.loop.time() - started)
            await asyncio.sleep(max(0.0, pause))

    def _tick_once(self):
        """One frame, if the hub is free: 'closed' (no page open), 'hidden' (none in sight),
        'busy' (a request holds the hub), 'failed' or 'ticked'."""
        if not self.hub_lock.acquire(blocking=False):
            return 'busy'
        try:
            if not self.hub.active:
                return 'closed'
            if not self.hub.watched:
                return 'hidden'
            self.hub.tick()
            return 'ticked'
        except Exception as error:  # noqa: BLE001 - the stream goes on after a bad frame
            self.log.error('studio: the stream failed: %r', error, exc_info=True)
            return 'failed'
        finally:
            self.hub_lock.release()
