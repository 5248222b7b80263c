"""Stream traffic shared by every simulator: packing payloads, and the per-cycle handshake.

:class:`Traffic` decides, cycle by cycle, what the source offers and whether the sink is ready,
with random ``valid`` gaps and ``ready`` stalls from a seed; it records what crossed each
interface. The Amaranth test bench and the cocotb test bench both drive it, so the same
vectors run the same way on every simulator.
"""
import random

import numpy as np

COUNTERS = ("culled", "loading")     # a scene pipeline's status counters, read at the end


def timed_rows(inputs):
    """Which rows start the latency: every row, or (a scene pipeline's stream, with host
    writes) the triangles, ``cmd = 0``."""
    return None if "cmd" not in inputs else [c == 0 for c in inputs["cmd"]]


__all__ = ["pack", "unpack", "Traffic", "StreamError", "Memory", "memory_ports", "COUNTERS",
           "timed_rows"]


class StreamError(RuntimeError):
    pass


def pack(fields, arrays):
    """Rows of field arrays -> payload integers (first field in the least significant bits)."""
    n = len(arrays[fields[0]["name"]]) if fields else 0
    words = [0] * n
    offset = 0
    for f in fields:
        mask = (1 << f["width"]) - 1
        col = np.asarray(arrays[f["name"]], np.int64).tolist()
        for k in range(n):
            words[k] |= (col[k] & mask) << offset
        offset += f["width"]
    return words


def unpack(fields, words):
    out, offset = {}, 0
    for f in fields:
        w, mask = f["width"], (1 << f["width"]) - 1
        col = [(word >> offset) & mask for word in words]
        if f["signed"]:
            col = [v - (1 << w) if v >> (w - 1) else v for v in col]
        out[f["name"]] = np.array(col, dtype=np.int64)
        offset += w
    return out


class Traffic:
    """The source and sink of one unit under test, with random valid gaps and ready stalls.

    ``drive()`` gives ``(valid, payload, ready)`` to set before a clock edge; ``edge(i_ready,
    o_valid, o_payload)`` takes what was sampled at that edge. The source holds its payload
    until it is accepted, as the stream rules require.
    """

    def __init__(self, words, *, p_valid=1.0, p_ready=1.0, seed=0, max_cycles=None,
                 progress=None, many=False, timed=None):
        self.words = words
        self.many = many                  # outputs per input vary: done when idle (``busy`` low)
        self.busy = True
        self.quiet = 0                    # cycles since the last handshake (the watchdog)
        self.progress = progress          # called as progress(inputs sent, outputs) now and then
        self.rng = random.Random(seed)
        self.p_valid, self.p_ready = p_valid, p_ready
        self.sent = 0
        self.valid = False
        self.ready = False
        self.out = []
        self.cycles = 0
        self.first_in = self.first_out = None
        self.timed = timed                # per row: whether it starts the latency (not a write)
        self.max_cycles = max_cycles or (64 + 4 * len(words) / max(1e-3, p_valid * p_ready))

    @property
    def done(self):
        if self.many:
            return self.sent >= len(self.words) and not self.busy
        return len(self.out) >= len(self.words)

    def drive(self):
        if not self.valid and self.sent < len(self.words):
            self.valid = self.p_valid >= 1.0 or self.rng.random() < self.p_valid
        self.ready = self.p_ready >= 1.0 or self.rng.random() < self.p_ready
        payload = self.words[self.sent] if self.valid else 0
        return int(self.valid), payload, int(self.ready)

    def edge(self, i_ready, o_valid, o_payload, busy=None):
        """``busy`` (units with ``many`` outputs per input): the unit's busy port this cycle."""
        taken = self.valid and i_ready
        moved = taken or (o_valid and self.ready)
        if self.valid and i_ready:
            if self.first_in is None and (self.timed is None or self.timed[self.sent]):
                self.first_in = self.cycles
            self.sent += 1
            self.valid = False
        if o_valid and self.ready:
            if self.first_out is None:
                self.first_out = self.cycles
            self.out.append(o_payload)
        self.cycles += 1
        if self.progress and not self.cycles & 1023:
            self.progress(self.sent, len(self.out))
        if self.many:
            self.busy = bool(busy) or bool(o_valid) or taken      # busy is sampled before
            self.quiet = 0 if moved else self.quiet + 1
            if self.quiet > 100_000:
                raise StreamError(f"no progress for 100,000 cycles: {self.sent} of "
                                  f"{len(self.words)} inputs sent, {len(self.out)} outputs")
        elif self.cycles > self.max_cycles:
            raise StreamError(f"no progress: {len(self.out)} of {len(self.words)} outputs after "
                              f"{self.cycles} cycles")

    @property
    def latency(self):
        """Cycles from the first accepted input (``timed``: the first accepted triangle, not a
        host write) to the first output (ready held high)."""
        return None if self.first_out is None else self.first_out - self.first_in


class Memory:
    """The texture memory behind a memory port, as every harness models it: ``words`` (the
    image), ``line`` responses per request (a line's texels in order), ``latency`` clocks from
    a request's acceptance to its first response, and random stalls: each clock it takes a
    request, and offers the next response, with chance ``p_ready``. Requests are answered in
    order. ``reads``: the words read. The Python harnesses step it (``drive``, ``edge``);
    the batch harness has the same model in C++."""

    def __init__(self, words, line=1, latency=12, p_ready=1.0, seed=0):
        if latency < 1 or not 0 < p_ready <= 1:
            raise ValueError(f"memory latency must be >= 1 and p_ready in (0, 1], not "
                             f"{latency}, {p_ready}")
        self.words = np.asarray(words, np.int64)
        self.line, self.latency, self.p_ready = int(line), int(latency), float(p_ready)
        self.seed = seed
        self.rng = random.Random(seed ^ 0x5eed)
        self.bursts = []                # [due cycle, address, next word]
        self.resp_valid, self.resp_data, self.take, self.reads = False, 0, False, 0
        self.held = None

    def with_line(self, line):
        """The same memory, answering ``line`` words per request (the cache's line)."""
        self.line = int(line)
        return self

    def ports(self, n):
        """``n`` readers of this memory, each a port with stalls of its own (the first is
        this one)."""
        out = [self]
        for k in range(1, n):
            port = Memory(self.words, self.line, self.latency, self.p_ready, self.seed + k)
            out.append(port)
        return out

    def drive(self):
        """``(request ready, response valid, response data)`` to set before a clock edge."""
        self.take = self.p_ready >= 1 or self.rng.random() < self.p_ready
        return self.take, self.resp_valid, self.resp_data

    def edge(self, cycle, req_valid, req_addr, resp_ready):
        """What was sampled at the edge of ``cycle``: the request, the response's ready."""
        if self.held is not None and (not req_valid or req_addr != self.held):
            raise StreamError(f"a stalled memory request changed or was withdrawn before it "
                              f"was taken (cycle {cycle})")
        self.held = req_addr if req_valid and not self.take else None
        moved = False
        if req_valid and self.take:
            if req_addr % self.line or req_addr + self.line > len(self.words):
                raise StreamError(f"a memory request at {req_addr} outside the texture memory "
                                  f"or not aligned to a line (cycle {cycle})")
            self.bursts.append([cycle + self.latency, req_addr, 0])
            moved = True
        if self.resp_valid and resp_ready:
            self.resp_valid, moved = False, True
        if not self.resp_valid and self.bursts and self.bursts[0][0] <= cycle + 1 and \
                (self.p_ready >= 1 or self.rng.random() < self.p_ready):
            b = self.bursts[0]
            self.resp_data, self.resp_valid = int(self.words[b[1] + b[2]]), True
            self.reads += 1
            b[2] += 1
            if b[2] == self.line:
                self.bursts.pop(0)
        return moved

    @property
    def busy(self):
        return self.resp_valid or bool(self.bursts)


def memory_ports(unit):
    """A unit's texture memory ports: ``[(request stream, response stream)]`` by name."""
    return [(n, "tex_resp" + n[len("tex_req"):]) for n in unit.stream_ports
            if n.startswith("tex_req")]
