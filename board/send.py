"""``python -m board send SCENE.toml --port /dev/ttyUSB0``: a scene to the board over the
FT231X (pyserial, 3 Mbaud, 8N1): a clear, the scene's data, its triangles and a status frame,
each sent once the last one's reply has come (one credit: the link's buffer holds one
frame), and sent again, up to ``RETRIES`` times, when its reply is a rejection or does not
come within ``REPLY_S``.
"""
import sys
import time

from .link import REPLY_BYTES
from .protocol import Encoder, parse_reply
from .top import BAUD

__all__ = ["send", "Host"]

RETRIES = 4
REPLY_S = 0.5


class Host:
    """Frames over a byte port (``write``, ``read``: a ``serial.Serial`` or a test's)."""

    def __init__(self, port):
        self.port = port
        self.last = None

    def exchange(self, data, seq):
        for attempt in range(RETRIES + 1):
            self.port.write(data)
            reply = parse_reply(self.port.read(REPLY_BYTES))
            if reply is not None and reply["seq"] == seq and reply["result"] == "ok":
                self.last = reply
                return reply
            time.sleep(0.01)                 # the line quiet: the link drops what is left
            self.port.reset_input_buffer()
        raise OSError(f"frame {seq}: no good reply after {RETRIES + 1} tries "
                      f"(last: {reply})")


def send(scene_path, port, size=None, board="ulx3s-25f"):
    import serial
    from tqdm import tqdm
    from .sim import prepare
    prep, core = prepare(scene_path, size, board)
    frames = Encoder(core.pipe, core.buffer).scene(prep)
    with serial.Serial(port, BAUD, timeout=REPLY_S) as line:
        host = Host(line)
        t0 = time.time()
        for data in tqdm(frames, unit="frame", desc="board send", file=sys.stderr):
            host.exchange(data, data[3])
    n = prep["triangles"]["drawn"]
    print(f"{len(frames)} frames, {n} triangles in {time.time() - t0:.2f} s; the link's "
          f"counters: {host.last}")
