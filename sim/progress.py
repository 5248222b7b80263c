"""Progress on stderr for rows streamed through a unit: a tqdm bar, fed by the Amaranth bench
directly, or by polling the small file the cocotb bench rewrites now and then."""
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from tqdm import tqdm


class Progress:
    """``progress(sent, outputs)``: inputs accepted and outputs received so far. For a unit
    with many outputs per input (``many``) the bar counts inputs and shows the outputs."""

    def __init__(self, label, total, many=False, unit="row"):
        self.many = many
        self.bar = tqdm(total=total, desc=label, unit=unit, file=sys.stderr, mininterval=0.5,
                        dynamic_ncols=True, leave=False)

    def __call__(self, sent, outputs):
        done = sent if self.many else outputs
        self.bar.update(done - self.bar.n)
        if self.many:
            self.bar.set_postfix_str(f"{outputs:,} out", refresh=False)

    def close(self):
        self.bar.close()


@contextmanager
def watch(path, progress, every=0.5):
    """While the block runs, feed ``progress`` from the ``sent outputs`` line at ``path``."""
    path, stop = Path(path), threading.Event()

    def poll():
        while not stop.wait(every):
            try:
                sent, outputs = map(int, path.read_text().split())
            except (OSError, ValueError):
                continue
            progress(sent, outputs)

    thread = threading.Thread(target=poll, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def report_to(path):
    """The bench side of :func:`watch`: a callback that rewrites ``path`` atomically."""
    path, tmp, last = Path(path), Path(f"{path}.tmp"), [0.0]

    def write(sent, outputs):
        now = time.monotonic()
        if now - last[0] >= 0.25:
            last[0] = now
            tmp.write_text(f"{sent} {outputs}")
            tmp.replace(path)
    return write
