"""A studio client without a browser, for bench_studio.py: takes the stream until stopped.

    python bench/studio_stream_client.py URL     # URL: the page's address with its token
"""
import asyncio
import sys
import urllib.parse

import aiohttp


async def take_stream(url):
    parts = urllib.parse.urlsplit(url)
    base = '%s://%s' % (parts.scheme, parts.netloc)
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(base + '/ws?' + parts.query, headers={'Origin': base}) as socket:
            async for _message in socket:
                pass


if __name__ == '__main__':
    try:
        asyncio.run(take_stream(sys.argv[1]))
    except KeyboardInterrupt:
        pass
