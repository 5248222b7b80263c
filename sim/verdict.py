"""A unit's outputs against its golden model, as a user reads it: the verdict first, then per
field the worst error as a fraction of its derived bound, and the error and bound in the
field's own unit (degrees for angles)."""
import numpy as np

from golden import MODELS


def amount(raw, fmt):
    """A raw error (LSB of ``fmt``) in the field's unit: ``0.176 deg``, ``0.000516``."""
    if fmt is None:
        return f"{raw:.3g}"
    value = raw * fmt.lsb
    if fmt.unit == "turn":
        return f"{value * 360:.3g} deg"
    return f"{value:.3g}" if fmt.unit == "1" else f"{value:.3g} [{fmt.unit}]"


def judge(unit, inputs, outputs):
    """``(ok, worst, lines)``: whether every row is within its bound, the worst error/bound
    over every field, and one line per field."""
    result = MODELS[unit.NAME].check(inputs, outputs, **unit.params)
    fmts = {f.name: f.fmt for f in unit.outputs}
    ok, worst, lines = True, 0.0, []
    for field, (err, bound) in result.items():
        err = np.asarray(err, float)
        bound = np.broadcast_to(np.asarray(bound, float), err.shape)
        if not len(err):
            lines.append(f"{field:10} no rows")
            continue
        over = err > bound + 1e-9
        ok &= not over.any()
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(bound > 0, err / np.where(bound > 0, bound, 1),
                             np.where(err > 0, np.inf, 0.0))
        k = int(np.argmax(ratio))
        worst = max(worst, float(ratio[k]))
        fmt = fmts.get(field)
        if field == "coverage":
            text = "differs from the coverage rule" if over.any() else \
                "identical to the coverage rule"
        elif not bound.any():
            text = (f"bit-exact: all {len(err):,} rows" if not over.any() else
                    f"{int(over.sum()):,} of {len(err):,} rows differ (bit-exact unit), "
                    f"largest by {amount(float(err.max()), fmt)}")
        else:
            text = (f"{ratio[k]:.2f} of its bound: error {amount(float(err[k]), fmt)}, bound "
                    f"there {amount(float(bound[k]), fmt)} (bounds {amount(float(bound.min()), fmt)}"
                    f"..{amount(float(bound.max()), fmt)}, largest error "
                    f"{amount(float(err.max()), fmt)})")
            if over.any():
                text += f"; {int(over.sum()):,} rows over their bound"
        lines.append(f"{field:10} {text}")
    return ok, worst, lines
