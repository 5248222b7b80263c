"""``python -m golden.accuracy``: what the Fenney methods cost in accuracy, with plots.

Prints three tables and writes their plots to ``build/accuracy/``:

1. the power approximation against the true power curves (which exponent each C stands for);
2. the dot product against the true cosine, plain (the patent's L1-scaled vector) and
   renormalised, with the hardware's 8-bit encodings of normal and light;
3. the fixed-point bounds of the RTL against these float models, per parameter setting.
"""
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hdl.illum_unit.fenney_dot import rsqrt_lut  # noqa: E402
from hdl.lut import quarter_cos_lut  # noqa: E402

from . import fenney  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "build" / "accuracy"
C_TABLE = (0, 1, 8, 16, 32, 64, 96, 128, 160, 192, 224, 255)


def power_table(out):
    print("1. Power approximation P(X, C) against x**n (X, P as 10-bit fractions)")
    print(f"   {'C':>4} {'n (least squares)':>18} {'max |P - x**n| (LSB)':>22} "
          f"{'n (same half point)':>20}")
    fits = {}
    for c in C_TABLE:
        n_fit, err, n_half = fenney.power_exponent(c)
        fits[c] = n_fit
        print(f"   {c:4d} {n_fit:18.2f} {err:22.1f} {n_half:20.2f}")
    x = np.arange(1024)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for c, colour in zip((0, 32, 128, 255), ("C0", "C1", "C2", "C3")):
        ax.plot(x / 1023, fenney.power_int(x, c) / 1023, colour, label=f"P, C = {c}")
        ax.plot(x / 1023, (x / 1023) ** fits[c], colour + "--", lw=1,
                label=f"x^{fits[c]:.1f}")
    ax.set(xlabel="X (dot product)", ylabel="P", title="Fenney power approximation vs x^n")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "fenney_power.png", dpi=120)
    plt.close(fig)


def dot_table(out, n=200_000):
    print("\n2. Dot product against the true cosine (h = 1; unit normals on the hemisphere "
          "and unit lights,\n   encoded as texels and as int(127 l); error in LSBs of X, "
          "1024 = 1.0)")
    errs = fenney.true_cosine_error(n)
    for normalize, (mx, rms) in errs.items():
        label = "renormalised" if normalize else "plain (patent)"
        print(f"   {label:16} max {mx:7.1f}  rms {rms:6.1f}")
    # error against the elevation of the normal, for the plot
    rng = np.random.default_rng(1)
    nrm = rng.normal(size=(20_000, 3))
    nrm[:, 1] = np.abs(nrm[:, 1])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    inp = fenney.texel_decode(*fenney.texel_encode(nrm))
    li = np.trunc(nrm * 127).astype(np.int64)          # light along the normal: cos = 1
    inp.update(lx=li[:, 0], ly=li[:, 1], lz=li[:, 2], h=np.full(len(nrm), 255))
    elev = np.degrees(np.arcsin(nrm[:, 1]))
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for normalize, label in ((False, "plain (L1-scaled)"), (True, "renormalised")):
        ax.scatter(elev, fenney.dot_float(inp, normalize) / 1024, s=1, label=label)
    ax.set(xlabel="elevation of the normal (deg)", ylabel="N . L with L = N (true: 1)",
           title="Fenney X/Z dot product, light along the normal")
    ax.legend(markerscale=8)
    fig.tight_layout()
    fig.savefig(out / "fenney_dot.png", dpi=120)
    plt.close(fig)


def bound_table():
    print("\n3. RTL against the float models: derived bounds (LSB of the output)")
    for t in (8, 9, 10, 12):
        lut = quarter_cos_lut(t)
        print(f"   fenney_polar trig_bits={t:2d}: table error {lut.max_error:.3f} LSB of 2^-{t},"
              f" intensity bound {fenney.polar_bound(t):.3f}")
    rng = np.random.default_rng(3)
    dec = fenney.texel_decode(rng.integers(0, 255, 100_000), rng.integers(0, 255, 100_000))
    valid = dec.pop("invalid") == 0
    inp = {k: v[valid] for k, v in dec.items()}
    m = int(valid.sum())
    inp.update(lx=np.full(m, 127), ly=np.full(m, 127), lz=np.full(m, 127), h=np.full(m, 255))
    print(f"   fenney_dot plain: bound {fenney.dot_bound(inp).max():.3f} (valid texels)")
    for bits in (10, 12, 14, 16):
        lut = rsqrt_lut(bits)
        b = fenney.dot_bound(inp, True, bits).max()
        print(f"   fenney_dot normalize rsqrt_bits={bits:2d}: {lut.depth:6d} x 16-bit table, "
              f"error {lut.max_error:6.2f} LSB of g, bound {b:.3f} (valid texels)")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m golden.accuracy", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    power_table(args.out)
    dot_table(args.out)
    bound_table()
    print(f"\nplots: {args.out / 'fenney_power.png'}, {args.out / 'fenney_dot.png'}")


if __name__ == "__main__":
    main()
