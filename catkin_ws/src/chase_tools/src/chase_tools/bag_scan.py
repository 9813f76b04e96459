"""A ROS 1 bag's messages, from its index or, for a bag never closed or cut short, by scanning
its records one by one. rosbags reads an indexed bag; the scan reads what rosbags cannot.

No ROS here.
"""
import bz2
import mmap
import os
import struct
from dataclasses import dataclass

import lz4.frame
from rosbags.rosbag1 import Reader, ReaderError
from rosbags.typesys.msg import normalize_msgtype

from flatsim.errors import FlatsimError


@dataclass
class RawMessage:
    topic: str
    msgtype: str                               # normalised: pkg/msg/Type
    msgdef: str
    time_ns: int                               # the bag's receive time
    data: bytes


BAG_MAGIC = b'#ROSBAG V2.0\n'
_OP_MSG_DATA, _OP_CHUNK, _OP_CONNECTION = 0x02, 0x05, 0x07


def _header_fields(blob):
    fields = {}
    pos = 0
    while pos + 4 <= len(blob):
        (size,) = struct.unpack_from('<I', blob, pos)
        pos += 4
        name, sep, value = bytes(blob[pos:pos + size]).partition(b'=')
        if not sep or pos + size > len(blob):
            raise ValueError('bad header field')
        fields[name.decode()] = value
        pos += size
    return fields


def _records(buf, pos):
    """(header fields, data, complete) of each record from pos; the last may be incomplete."""
    end = len(buf)
    while pos + 4 <= end:
        (header_len,) = struct.unpack_from('<I', buf, pos)
        if pos + 8 + header_len > end:
            return
        try:
            header = _header_fields(buf[pos + 4:pos + 4 + header_len])
        except (ValueError, UnicodeDecodeError):
            return
        (data_len,) = struct.unpack_from('<I', buf, pos + 4 + header_len)
        start = pos + 8 + header_len
        complete = start + data_len <= end
        yield header, buf[start:min(start + data_len, end)], complete
        if not complete:
            return
        pos = start + data_len


def _decompress(compression, data, complete):
    if compression == b'none':
        return bytes(data)
    if compression == b'lz4':
        return lz4.frame.LZ4FrameDecompressor().decompress(bytes(data)) if not complete \
            else lz4.frame.decompress(bytes(data))
    if compression == b'bz2':
        return bz2.BZ2Decompressor().decompress(bytes(data))
    raise ValueError('compression %r' % compression.decode(errors='replace'))


def scan_bag(path, notes):
    """Every message a ROS 1 bag holds, read record by record without its index.

    For bags that were never closed or were cut short: the index at the end
    is missing, but the chunks before it are intact, and so is the start of a
    chunk that was cut.
    """
    with open(path, 'rb') as stream:
        size = os.fstat(stream.fileno()).st_size
        if stream.read(len(BAG_MAGIC)) != BAG_MAGIC or size <= len(BAG_MAGIC):
            raise FlatsimError('%s is not a ROS 1 bag (it does not start with %r)'
                               % (path, BAG_MAGIC.decode().strip()))
        with mmap.mmap(stream.fileno(), 0, access=mmap.ACCESS_READ) as buf:
            yield from _scan_records(buf, len(BAG_MAGIC), size, notes)


def _scan_records(buf, start, size, notes):
    connections = {}
    cut = False
    for header, data, complete in _records(buf, start):
        op = header.get('op', b'\0')[0]
        if op == _OP_CHUNK:
            try:
                body = _decompress(header.get('compression', b'none'), data, complete)
            except (ValueError, RuntimeError, OSError, EOFError) as err:
                notes.append('a chunk of the bag could not be decompressed (%s); skipped' % err)
                continue
            inner_complete = True
            for inner, inner_data, inner_ok in _records(body, 0):
                inner_complete = inner_ok
                if not inner_ok:
                    break
                message = _message_record(inner, inner_data, connections)
                if message is not None:
                    yield message
            cut = cut or not complete or not inner_complete
        else:
            message = _message_record(header, data, connections) if complete else None
            if message is not None:
                yield message
            cut = cut or not complete
    if cut:
        notes.append('the bag is cut short: its last record is incomplete at byte %d; '
                     'everything before it is reported' % size)


def _message_record(header, data, connections):
    op = header.get('op', b'\0')[0]
    if op == _OP_CONNECTION:
        fields = _header_fields(data)
        conn = struct.unpack('<I', header['conn'])[0]
        connections[conn] = (fields.get('topic', header.get('topic', b'')).decode(),
                             normalize_msgtype(fields['type'].decode()),
                             fields.get('message_definition', b'').decode())
    elif op == _OP_MSG_DATA:
        conn = struct.unpack('<I', header['conn'])[0]
        if conn in connections:
            secs, nsecs = struct.unpack('<II', header['time'])
            topic, msgtype, msgdef = connections[conn]
            return RawMessage(topic, msgtype, msgdef, secs * 10**9 + nsecs, bytes(data))
    return None


def bag_messages(path, notes):
    """Every message of the bag at path; problems are appended to notes.

    Raises FlatsimError only if the file is not a ROS 1 bag at all.
    """
    with open(path, 'rb') as stream:
        if stream.read(len(BAG_MAGIC)) != BAG_MAGIC:
            raise FlatsimError('%s is not a ROS 1 bag (it does not start with %r)'
                               % (path, BAG_MAGIC.decode().strip()))
    try:
        reader = Reader(path)
        reader.open()
    except ReaderError:
        notes.append('the bag has no usable index: it was not closed, or it is cut short; '
                     'its records are read one by one')
        yield from scan_bag(path, notes)
        return
    try:
        for conn, time_ns, data in reader.messages():
            yield RawMessage(conn.topic, conn.msgtype, conn.msgdef.data, time_ns, data)
    except ReaderError as err:
        notes.append('reading stopped early: %s' % err)
    finally:
        reader.close()
