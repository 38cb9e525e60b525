"""The UDP reader: every ready datagram in one chunk per wake-up, and no reading while the
queue holds its limit of chunks (the backlog stays in the socket)."""

from __future__ import annotations

import asyncio

from live.streams import udp_send
from live.streams import wait_for
from seatrack.live.sources import UDP_PAUSE_S
from seatrack.live.sources import UDP_PENDING
from seatrack.live.sources import Chunk
from seatrack.live.sources import Source
from seatrack.live.sources import open_udp


def test_udp_reader_batches_and_pauses_on_a_full_queue():
    async def go():
        queue: asyncio.Queue[Chunk] = asyncio.Queue()
        reader = await open_udp(Source("udp", "127.0.0.1", 0), queue, lambda c: None)
        port = reader.get_extra_info("sockname")[1]
        for _ in range(UDP_PENDING):
            queue.put_nowait(Chunk("x", [], 0.0, 0.0))
        udp_send(port, [b"a\nb", b"c\r\n", b"d"])
        await asyncio.sleep(20 * UDP_PAUSE_S)
        assert queue.qsize() == UDP_PENDING and reader.paused  # nothing read
        while not queue.empty():
            queue.get_nowait()
        await wait_for(lambda: not queue.empty())
        chunk = queue.get_nowait()
        assert chunk.lines == [b"a", b"b", b"c", b"d"] and not reader.paused
        reader.close()

    asyncio.run(asyncio.wait_for(go(), 10))
