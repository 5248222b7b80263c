"""The host side of the link (``board/link.py``): a prepared scene as frames, and a host that
sends them one at a time, each after the last one's reply.

The same frames feed the simulation (``board/sim.py``) and the board (``python -m board
send``): a clear, the scene's data load (``scene/host.py``'s writes), its triangles, and a
status frame.
"""
import struct

import numpy as np

from scene import host

from .link import (CLEAR_BYTES, COUNTERS, KINDS, REPLY_BYTES, REPLY_MAGIC, RESULTS, SYNC,
                   WRITE_BYTES, crc16)

__all__ = ["frame", "Encoder", "parse_reply", "known_ranges"]


def frame(kind, seq, payload=b""):
    """One frame's bytes: sync, header, payload, CRC."""
    body = struct.pack("<BBH", KINDS[kind], seq & 0xFF, len(payload)) + bytes(payload)
    return bytes(SYNC) + body + struct.pack("<H", crc16(body))


def parse_reply(raw):
    """A reply's bytes to ``{"seq", "result", counters...}``; None if it is not one."""
    if len(raw) != REPLY_BYTES or raw[0] != REPLY_MAGIC or raw[2] >= len(RESULTS):
        return None
    counts = struct.unpack(f"<{len(COUNTERS)}H", bytes(raw[3:]))
    return {"seq": raw[1], "result": RESULTS[raw[2]], **dict(zip(COUNTERS, counts))}


def known_ranges(pipeline):
    """``(base, size)`` of every address the pipeline's map names (docs/host.md)."""
    out = [(host.REGISTERS, len(pipeline.registers))] if pipeline.registers else []
    out += [(base, lut.depth) for base, _, _, lut in host.tables(pipeline.stages)]
    for s in pipeline.stages:
        if "texture" in s.tables:
            out.append((host.TEXTURE, s.tables["texture"].depth))
    return out


class Encoder:
    """Frames for one pipeline: ``payload`` bytes at most a frame (the link's buffer)."""

    def __init__(self, pipeline, payload=2048):
        self.fields = list(pipeline.raster.unit.inputs)
        self.tri_bits = sum(f.fmt.width for f in self.fields)
        self.tri_bytes = (self.tri_bits + 7) // 8
        self.payload = payload
        self.seq = 0

    def _next(self, kind, payload=b""):
        out = frame(kind, self.seq, payload)
        self.seq = (self.seq + 1) & 0xFF
        return out

    def triangles(self, inputs):
        """Records of the raster's fields, each packed LSB first in its fields' order."""
        n = len(next(iter(inputs.values())))
        words = [0] * n
        shift = 0
        for f in self.fields:
            v = np.asarray(inputs[f.name], np.int64) & ((1 << f.fmt.width) - 1)
            for k in range(n):
                words[k] |= int(v[k]) << shift
            shift += f.fmt.width
        return [w.to_bytes(self.tri_bytes, "little") for w in words]

    @staticmethod
    def writes(addr, data):
        return [struct.pack("<I", int(a))[:3] + struct.pack("<I", int(d) & 0xFFFFFFFF)
                for a, d in zip(addr, data)]

    def chunks(self, kind, records):
        """Records into frames of as many whole records as a frame holds."""
        size = len(records[0]) if records else 1
        per = max(1, self.payload // size)
        return [self._next(kind, b"".join(records[k:k + per]))
                for k in range(0, len(records), per)]

    def clear(self, background):
        rgb = np.rint(np.array(background) * 255).astype(np.int64)
        word = (rgb[0] >> 3) << 11 | (rgb[1] >> 2) << 5 | rgb[2] >> 3
        return self._next("clear", struct.pack("<H", int(word)))

    def status(self):
        return self._next("status")

    def scene(self, prep):
        """A prepared scene's frames: clear, its data, its triangles, a status."""
        addr, data = prep["load"]
        return ([self.clear(prep["scene"]["image"]["background"])]
                + self.chunks("writes", self.writes(addr, data))
                + self.chunks("triangles", self.triangles(prep["inputs"]))
                + [self.status()])


assert WRITE_BYTES == 7 and CLEAR_BYTES == 2
