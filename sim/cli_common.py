"""What ``python -m sim`` and ``python -m golden`` share: reading and writing npz vectors
against a unit's fields, the summary line of a run, and turning a user's mistake into one clear
line and exit code 2 (Ctrl-C: one line and exit code 130)."""
import os
import sys
import zipfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from hdl.fixed import FieldError, check_arrays
from hdl.span_unit.plan import KNOBS
from hdl.units import ParamError
from scene.driver import SceneError
from scene.stage import StageError

from .batch import BatchError
from .stream import StreamError

NPZ_MAGIC = (b"PK\x03\x04", b"PK\x05\x06")     # a zip (np.savez), or an empty zip
NPY_MAGIC = b"\x93NUMPY"


class UsageError(Exception):
    pass


def read_npz(path):
    """``{name: array}`` from an npz file, or a UsageError that says what the file is."""
    path = Path(path)
    if not path.exists():
        raise UsageError(f"{path}: no such file")
    if path.is_dir():
        raise UsageError(f"{path}: is a directory, not an npz file")
    with open(path, "rb") as f:
        head = f.read(6)
    if head == NPY_MAGIC:
        raise UsageError(f"{path}: is a single .npy array; give an npz with one array per "
                         f"field, as np.savez(path, name=array, ...) writes")
    if head[:4] not in NPZ_MAGIC:
        raise UsageError(f"{path}: not an npz file (an npz is a zip of .npy arrays, as "
                         f"np.savez writes; this one starts with {head[:4]!r})")
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except (ValueError, OSError, EOFError, KeyError, zipfile.BadZipFile) as e:
        raise UsageError(f"{path}: not a readable npz file, truncated or corrupt "
                         f"({type(e).__name__}: {e})") from None


def read_fields(fields, path, name, what="input"):
    """The arrays of ``path`` checked against ``fields``; warns about extra ones."""
    arrays, extra = check_arrays(fields, read_npz(path), where=str(path))
    if extra:
        print(f"warning: {path}: ignoring field(s) {', '.join(extra)} that are not {name}'s "
              f"{what}s", file=sys.stderr)
    return arrays


def read_inputs(unit, path):
    inputs = read_fields(unit.inputs, path, unit.NAME)
    if not rows(inputs):
        print(f"note: {path} has 0 rows: the outputs will have 0 rows too", file=sys.stderr)
    return inputs


def unit_names(text, known):
    """``--units a,b`` -> a list of registered unit names (all of them when not given)."""
    names = text.split(",") if text else list(known)
    bad = [n for n in names if n not in known]
    if bad:
        raise UsageError(f"--units: unknown unit {bad[0]!r}; known: {', '.join(known)}")
    return names


def rows(arrays):
    return len(next(iter(arrays.values()))) if arrays else 0


def check_output_path(path, option="--out"):
    """Fail before any work if ``path`` cannot be written (written exactly as given)."""
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise UsageError(f"{option} {path}: is a directory; give a file name")
    if not parent.is_dir():
        raise UsageError(f"{option} {path}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UsageError(f"{option} {path}: directory {parent} is not writable")


def write_outputs(unit, path, outputs):
    arrays = {}
    for f in unit.outputs:
        a = np.asarray(outputs[f.name])
        if a.dtype.kind == "f":
            a = np.rint(a)
        arrays[f.name] = np.clip(a, f.fmt.min, f.fmt.max).astype(np.int64)
    with open(path, "wb") as f:                 # exactly this name (np.savez adds ".npz")
        np.savez(f, **arrays)


def summary(unit, inputs, outputs, culled=None):
    """``5,000 rows`` or, for a unit with many outputs per input, ``20 triangles (2 culled)
    -> 15,863 fragments``."""
    n = rows(inputs)
    if not unit.status_ports:
        return f"{n:,} rows"
    culled = "" if culled is None else f" ({culled:,} culled)"
    return f"{n:,} triangles{culled} -> {len(outputs['tri']):,} fragments"


@contextmanager
def user_errors():
    """Report a user's mistake as ``error: ...`` with exit code 2, not a traceback."""
    try:
        yield
    except (UsageError, FieldError, ParamError, SceneError, StageError) as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)
    except (BatchError, StreamError) as e:     # the RTL hung or broke a stream rule
        print(f"error: {e}", file=sys.stderr)
        sys.exit(1)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
    except BrokenPipeError:                    # output piped into head, say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)


# the raster plan's knobs (hdl.span_unit.plan), its reciprocal, and the vector channels'
# fraction bits (fenney_xz's)
RASTER_KNOBS = (*KNOBS, "recip", "recip_iters", "vector_bits")


def raster_knobs(text):
    """``--raster setup_ii=16,setup_mults=2``: the raster's build knobs (docs/quadratic.md),
    each checked by the pipeline's own ranges (``sim render``, ``flows.fpga``)."""
    out = {}
    for item in filter(None, (text or "").split(",")):
        key, sep, value = (x.strip() for x in item.partition("="))
        if not sep or key not in RASTER_KNOBS:
            raise UsageError(f"--raster: {item!r} is not KNOB=VALUE with a knob of "
                             f"{', '.join(RASTER_KNOBS)}")
        if key == "recip":
            out[key] = value
        elif value.isdigit():
            out[key] = int(value)
        else:
            raise UsageError(f"--raster: {key} must be a whole number, not {value!r}")
    return out
