"""The studio from outside the machine: `gazebo --listen 0.0.0.0:8080`, as docs/course.md shows
it for a lab server or a container, with the browser on another host.

Two network namespaces joined by a veth pair stand in for the two machines, on addresses of
their own: the simulator's (10.201.0.1) runs `gazebo --listen 0.0.0.0:8080` with a master of
its own on its own loopback; the student's (10.201.0.2) opens the page in Debian's chromium,
once straight at the simulator's address and once through a forwarded port on its own
loopback (127.0.0.1:9090 to 10.201.0.1:8080), which is what `ssh -L 9090:127.0.0.1:8080` and
`docker run -p 9090:8080` give a browser. The machine's real network is never touched.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import time

import pytest

from chase_tools.procs import ProcessGroup

SIMULATOR_HOST, BROWSER_HOST = '10.201.0.1', '10.201.0.2'
PORT, FORWARDED_PORT = 8080, 9090
# As docs/course.md shows it.
LISTEN_COMMAND = ['gazebo', '--listen', '0.0.0.0:%d' % PORT]
TESTS = os.path.dirname(os.path.abspath(__file__))

# Runs on the browser's host: argv[1] is the page's address as gazebo printed it.
BROWSER = r'''
import asyncio, json, socket, sys, threading, urllib.error, urllib.parse, urllib.request
from playwright.sync_api import sync_playwright
from studio_browser import launch_browser, new_page

printed, simulator, port, forwarded, profile = sys.argv[1:6]
token = urllib.parse.parse_qs(urllib.parse.urlsplit(printed).query)['token'][0]
found = {}

def status(url):
    try:
        return urllib.request.urlopen(url, timeout=10).status
    except urllib.error.HTTPError as error:
        return error.code

direct = 'http://%s:%s/' % (simulator, port)
found['without_token'] = status(direct)
found['wrong_token'] = status(direct + '?token=' + 'x' * len(token))
found['with_token'] = status(direct + '?token=' + token)

# The token from another site's page, even one whose name points at the simulator: refused.
import aiohttp

async def handshake(headers):
    async with aiohttp.ClientSession() as session:
        try:
            async with session.ws_connect(direct + 'ws?token=' + token, headers=headers) as socket:
                return json.loads((await socket.receive(timeout=10)).data)['type']
        except aiohttp.WSServerHandshakeError as error:
            return error.status

named = 'studio.example:%s' % port
found['other_site'] = asyncio.run(handshake({'Origin': 'http://example.org'}))
found['named_site'] = asyncio.run(handshake({'Origin': 'http://' + named, 'Host': named}))
found['own_page'] = asyncio.run(handshake({'Origin': 'http://%s:%s' % (simulator, port)}))

# A forwarded port, as ssh -L and docker run -p give: another address and port for the browser.
async def pipe(reader, writer):
    try:
        while data := await reader.read(65536):
            writer.write(data)
            await writer.drain()
    finally:
        writer.close()

async def forward(client_reader, client_writer):
    reader, writer = await asyncio.open_connection(simulator, int(port))
    await asyncio.gather(pipe(client_reader, writer), pipe(reader, client_writer))

loop = asyncio.new_event_loop()
server = loop.run_until_complete(asyncio.start_server(forward, '127.0.0.1', int(forwarded)))
threading.Thread(target=loop.run_forever, daemon=True).start()

with sync_playwright() as playwright:
    context = launch_browser(playwright, profile)
    for name, url in (('direct', direct), ('forwarded', 'http://localhost:%s/' % forwarded)):
        page = new_page(context, url + '?token=' + token)
        found[name] = {'ready': page.evaluate('() => document.body.dataset.ready'),
                       # A request that changes the simulator, answered over the page's WebSocket.
                       'paused': page.evaluate("""async () => {
                           const reply = await window.studio.connection.request('pause', {});
                           await window.studio.connection.request('play', {});
                           return reply.ok; }"""),
                       'errors': page.errors}
        page.close()
    context.close()
print(json.dumps(found), flush=True)
'''


def _ip(*args):
    return subprocess.run(['ip'] + list(args), capture_output=True, text=True)


@pytest.fixture
def two_hosts():
    """Namespaces (simulator's, browser's) joined by a veth pair; skipped where they cannot be made."""
    if os.geteuid() != 0:
        pytest.skip('network namespaces need root, which this run does not have')
    if shutil.which('ip') is None:
        pytest.skip('network namespaces need iproute2 (the ip command)')
    tag = os.getpid() % 100000
    names = ('studioS%d' % tag, 'studioB%d' % tag)
    veths = ('sts%d' % tag, 'stb%d' % tag)
    made = []
    try:
        for ns in names:
            added = _ip('netns', 'add', ns)
            if added.returncode != 0:
                pytest.skip('cannot create a network namespace: %s' % added.stderr.strip())
            made.append(ns)
        steps = [('link', 'add', veths[0], 'type', 'veth', 'peer', 'name', veths[1])]
        for ns, veth, host in zip(names, veths, (SIMULATOR_HOST, BROWSER_HOST)):
            steps += [('link', 'set', veth, 'netns', ns),
                      ('-n', ns, 'addr', 'add', host + '/24', 'dev', veth),
                      ('-n', ns, 'link', 'set', veth, 'up'),
                      ('-n', ns, 'link', 'set', 'lo', 'up')]
        for step in steps:
            done = _ip(*step)
            if done.returncode != 0:
                pytest.skip('cannot join the namespaces (ip %s): %s' % (' '.join(step), done.stderr.strip()))
        yield names
    finally:
        # Deleting a namespace deletes the veth end in it, and with it the pair.
        for ns in made:
            _ip('netns', 'delete', ns)


def _printed_address(path, timeout=90.0):
    """The page's address as gazebo printed it in its terminal (path), once it has."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with open(path) as out:
            found = re.search(r'http://\S+/\?token=\S+', out.read())
        if found:
            return found.group(0)
        time.sleep(0.3)
    return None


@pytest.mark.skipif(shutil.which('gazebo') is None, reason='needs the built workspace: source env.sh first')
def test_gazebo_listen_serves_the_page_to_another_host_with_a_warning_and_the_token(two_hosts, tmp_path):
    simulator_ns, browser_ns = two_hosts
    home = tmp_path / 'home'
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ('ROS_IP', 'DISPLAY', 'WAYLAND_DISPLAY')}
    env.update(HOME=str(home), ROS_HOME=str(home / '.ros'), ROS_HOSTNAME='localhost',
               ROS_MASTER_URI='http://localhost:11311')
    simulator = ProcessGroup(env)
    log_path = tmp_path / 'gazebo.log'
    with open(log_path, 'w') as log:
        try:
            simulator.start(['ip', 'netns', 'exec', simulator_ns] + LISTEN_COMMAND, log)
            printed = _printed_address(log_path)
            said = log_path.read_text()
            assert printed, said
            # On every address, so its own loopback is the address it gives.
            assert printed.startswith('http://127.0.0.1:%d/?token=' % PORT), said
            assert 'gazebo: warning: the studio listens on 0.0.0.0 port %d, not only on 127.0.0.1' % PORT \
                in said
            assert 'has the token can change the world' in said

            browser_env = dict(env, PYTHONPATH=TESTS + os.pathsep + env.get('PYTHONPATH', ''))
            run = subprocess.run(['ip', 'netns', 'exec', browser_ns, sys.executable, '-c', BROWSER, printed,
                                  SIMULATOR_HOST, str(PORT), str(FORWARDED_PORT), str(tmp_path / 'chromium')],
                                 env=browser_env, capture_output=True, text=True, timeout=180)
            assert run.returncode == 0, run.stderr[-3000:] + '\ngazebo: ' + log_path.read_text()[-3000:]
            found = json.loads(run.stdout.strip().splitlines()[-1])
            # The token stays required on the other address.
            assert found['without_token'] == 403
            assert found['wrong_token'] == 403
            assert found['with_token'] == 200
            assert found['other_site'] == 403
            assert found['named_site'] == 403
            assert found['own_page'] == 'hello'
            # The page works from the other host, straight and through a forwarded port.
            for way in ('direct', 'forwarded'):
                assert found[way]['ready'] == 'true', found
                assert found[way]['paused'] is True, found
                assert found[way]['errors'] == [], found
        finally:
            simulator.stop()
