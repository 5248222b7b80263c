"""What ``python -m sim`` and ``python -m golden`` share: reading and writing npz vectors
against a unit's fields, and turning a user's mistake into one clear line and exit code 2."""
import sys
from contextlib import contextmanager

import numpy as np

from hdl.fixed import FieldError, check_arrays
from hdl.units import ParamError


class UsageError(Exception):
    pass


def read_inputs(unit, path):
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise UsageError(f"{path}: no such file") from None
    except (ValueError, OSError) as e:
        raise UsageError(f"{path}: not a readable npz file ({e})") from None
    inputs, extra = check_arrays(unit.inputs, arrays, where=str(path))
    if extra:
        print(f"warning: {path}: ignoring field(s) {', '.join(extra)} that {unit.NAME} "
              f"does not take", file=sys.stderr)
    return inputs


def write_outputs(unit, path, outputs):
    arrays = {}
    for f in unit.outputs:
        a = np.asarray(outputs[f.name])
        if a.dtype.kind == "f":
            a = np.rint(a)
        arrays[f.name] = np.clip(a, f.fmt.min, f.fmt.max).astype(np.int64)
    np.savez(path, **arrays)


@contextmanager
def user_errors():
    """Report a user's mistake as ``error: ...`` with exit code 2, not a traceback."""
    try:
        yield
    except (UsageError, FieldError, ParamError) as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)
