"""``python -m golden.accuracy``: what the methods cost in accuracy, with plots.

Prints four tables and writes their plots to ``build/accuracy/``:

1. the power approximation against the true power curves (which exponent each C stands for);
2. the dot product against the true cosine, plain (the patent's L1-scaled vector) and
   renormalised, with the hardware's 8-bit encodings of normal and light;
3. the fixed-point bounds of the RTL against these float models, per parameter setting;
4. seed 003's published vector rotation against the exact rotation.
"""
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hdl.illum_unit.fenney_dot import rsqrt_lut  # noqa: E402
from hdl.lut import quarter_cos_lut  # noqa: E402

from . import angular, fenney  # noqa: E402

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


def rotation_table(out, n=200_000):
    print("\n4. Seed 003's published rotation against the exact rotation (float, no fixed "
          "point;\n   N and A uniform on the upper hemisphere), by the angle between N and A")
    rows, sep, angle = angular.method_error(n)
    print(f"   {'N-A angle':>10} {'count':>7} {'angle error (deg): mean':>24} {'p99':>7} "
          f"{'max':>7} {'|N.A error|: mean':>18} {'p99':>7} {'max':>7}")
    for lo, hi, cnt, a_mean, a_99, a_max, e_mean, e_99, e_max in rows:
        print(f"   {f'{lo}-{hi}':>10} {cnt:7d} {a_mean:24.2f} {a_99:7.2f} {a_max:7.2f} "
              f"{e_mean:18.4f} {e_99:7.4f} {e_max:7.4f}")
    fig, ax = plt.subplots(figsize=(7, 4.5))
    edges = np.arange(0, 91, 5)
    idx = np.digitize(sep, edges) - 1
    keep = (idx >= 0) & (idx < len(edges) - 1)
    centre = (edges[:-1] + edges[1:]) / 2
    for q, label in ((50, "median"), (99, "99th percentile"), (100, "maximum")):
        ax.plot(centre, [np.percentile(angle[keep & (idx == k)], q) for k in range(len(centre))],
                marker="o", label=label)
    ax.set(xlabel="angle between N and A (deg)", ylabel="angle between rotated vectors (deg)",
           title="Seed 003 rotation: method error against the exact rotation")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "rotation_method_error.png", dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m golden.accuracy", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    power_table(args.out)
    dot_table(args.out)
    bound_table()
    rotation_table(args.out)
    print("\nplots: " + ", ".join(str(args.out / f) for f in (
        "fenney_power.png", "fenney_dot.png", "rotation_method_error.png")))


if __name__ == "__main__":
    main()
