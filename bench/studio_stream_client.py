"""A studio client without a browser, for bench_studio.py: takes the stream until stopped.

    python bench/studio_stream_client.py URL     # URL: the page's address with its token

Stopped (SIGTERM or Ctrl-C), it prints how many pose messages a second it was sent
after the first (the full poses): the stream's rate as a tab receives it.
"""
import asyncio
import json
import signal
import sys
import time
import urllib.parse

import aiohttp


async def take_stream(url, seen):
    parts = urllib.parse.urlsplit(url)
    base = '%s://%s' % (parts.scheme, parts.netloc)
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(base + '/ws?' + parts.query, headers={'Origin': base}) as socket:
            async for message in socket:
                if message.type == aiohttp.WSMsgType.TEXT and json.loads(message.data)['type'] == 'poses':
                    seen.append(time.monotonic())


def main():
    seen = []
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    try:
        asyncio.run(take_stream(sys.argv[1], seen))
    except (KeyboardInterrupt, SystemExit):
        pass
    finally:
        rate = (len(seen) - 2) / (seen[-1] - seen[1]) if len(seen) > 2 and seen[-1] > seen[1] else 0.0
        print('poses per second: %.1f' % rate, flush=True)


if __name__ == '__main__':
    main()
