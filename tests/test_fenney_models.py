"""The Fenney models themselves: the patent's formulas, the decode policy, the method errors.

These check the golden models against closed forms and properties that follow from the patent
(no RTL is involved), so that an error in a model cannot hide behind the RTL agreeing with it.
"""
import numpy as np
from hypothesis import given, settings, strategies as st

from golden import fenney
from hdl.illum_unit.fenney_dot import rsqrt_lut
from hdl.lut import quarter_cos_lut

codes = st.integers(0, 255)


@given(codes, codes)
def test_decode_is_the_patent_formula_for_valid_texels(tx, tz):
    d = fenney.texel_decode(tx, tz)
    bx, bz = (tx - 127) * 2, (tz - 127) * 2
    if tx != 255 and tz != 255 and abs(bx) + abs(bz) <= 255:
        assert (d["x"], d["y"], d["z"], d["invalid"]) == (bx, 255 - abs(bx) - abs(bz), bz, 0)
        assert abs(d["x"]) + d["y"] + abs(d["z"]) == 255          # |x|+|y|+|z| = 1, scaled
    else:
        assert d["invalid"] == 1


def test_invalid_texels_stay_on_the_hemisphere():
    """Policy: code 255 decodes as 254, y saturates at 0; nothing wraps or overflows."""
    tx, tz = np.meshgrid(np.arange(256), np.arange(256), indexing="ij")
    d = fenney.texel_decode(tx.ravel(), tz.ravel())
    assert d["x"].min() == -254 and d["x"].max() == 254          # fits s9, never 256
    assert d["z"].min() == -254 and d["z"].max() == 254
    assert d["y"].min() == 0 and d["y"].max() == 255             # never wraps
    inv = d["invalid"] == 1
    # the valid set is the diamond |bx| + |bz| <= 255 over codes 0..254: |i| + |j| <= 127
    i, j = tx.ravel() - 127, tz.ravel() - 127
    valid = (tx.ravel() < 255) & (tz.ravel() < 255) & (np.abs(i) + np.abs(j) <= 127)
    assert np.array_equal(~inv, valid)
    assert np.all(d["y"][inv & (tx.ravel() < 255) & (tz.ravel() < 255)] == 0)
    # over-filtered texels keep the direction of (x, z) on the horizon
    k = np.flatnonzero(inv & (tx.ravel() == 200) & (tz.ravel() == 60))[0]
    assert (d["x"][k], d["y"][k], d["z"][k]) == (146, 0, -134)


def test_encode_decode_round_trip():
    """Encoding unit normals as the patent does and decoding them loses under one code step
    per component of the L1-scaled vector (int() truncation, then *2)."""
    rng = np.random.default_rng(0)
    v = rng.normal(size=(10_000, 3))
    v[:, 1] = np.abs(v[:, 1])
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    d = fenney.texel_decode(*fenney.texel_encode(v))
    assert not d["invalid"].any()
    l1 = v / np.abs(v).sum(axis=1, keepdims=True)
    assert np.abs(d["x"] / 254 - l1[:, 0]).max() < 1 / 127
    assert np.abs(d["z"] / 254 - l1[:, 2]).max() < 1 / 127


@given(st.integers(0, 1023), st.integers(0, 255))
def test_power_formula(x, c):
    k = c + 8
    lum = max(0, 1023 - ((k * (1023 - x)) >> 3))
    q = (lum * lum) >> 10
    assert fenney.power_int(x, c) == lum + ((c * (q - lum)) >> 8)   # the patent, line by line
    assert 0 <= fenney.power_int(x, c) <= lum <= 1023                 # Q <= L, so P <= L


def test_power_hard_cases():
    x = np.arange(1024)
    assert np.array_equal(fenney.power_int(x, 0), x)        # C = 0 is linear, exactly
    assert fenney.power_int(1023, 255) == 1022   # L = 1023, Q = 1046529 >> 10 = 1022, -255 >> 8 = -1
    assert fenney.power_int(0, 0) == 0 and fenney.power_int(0, 255) == 0
    for c in (0, 1, 128, 255):                              # monotone in X for every C
        assert np.all(np.diff(fenney.power_int(x, c)) >= 0)
    # more concentration never brightens
    cs = np.arange(256)[:, None]
    assert np.all(np.diff(fenney.power_int(x[None, :], cs), axis=0) <= 0)


def test_power_exponents_grow_with_concentration():
    fits = [fenney.power_exponent(c) for c in (0, 32, 64, 128, 192, 255)]
    assert fits[0][:2] == (1.0, 0.0) and abs(fits[0][2] - 1) < 0.01   # C = 0: P = X
    assert all(a[0] < b[0] and a[2] < b[2] for a, b in zip(fits, fits[1:]))


def test_plain_dot_is_short_for_diagonal_normals():
    """The L1-scaled bump vector of the diagonal normal has length 1/sqrt(3): the plain dot
    product with the light along it is 0.577, the renormalised one 1."""
    b = {"x": np.array([85]), "y": np.array([85]), "z": np.array([85])}
    light = np.round(np.array([1, 1, 1]) / np.sqrt(3) * 127).astype(int)
    inp = {**b, "lx": light[:1], "ly": light[1:2], "lz": light[2:], "h": np.array([255])}
    assert abs(fenney.dot_float(inp) / 1024 - 1 / np.sqrt(3)) < 0.01
    assert abs(fenney.dot_float(inp, normalize=True) / 1024 - 1) < 0.01


def test_renormalising_costs_less_accuracy_than_not():
    err = fenney.true_cosine_error(n=20_000)
    plain, renorm = err[False], err[True]
    assert renorm[0] < plain[0] / 5 and renorm[1] < plain[1] / 5
    # what remains is the 8-bit encodings: one code step of 1/127 per component
    assert renorm[1] < 1024 * 3 / 127


def test_polar_model_closed_forms():
    inp = {k: np.array([v]) for k, v in
           dict(s=0, r=0, q=0, k1=0, k2=0, k3=255).items()}
    assert fenney.polar_float(inp)[0] == 255                    # S = 0, R = Q: cos S cos 0
    inp["r"] = np.array([128])
    assert fenney.polar_float(inp)[0] == 0                      # R - Q = 180 deg clamps
    inp.update(s=np.array([128]), k2=np.array([255]), k3=np.array([0]))
    assert abs(fenney.polar_float(inp)[0] - 255 * np.sin(np.pi / 4)) < 1e-9


def test_table_errors_are_what_the_bounds_assume():
    assert quarter_cos_lut(10).max_error <= 0.5                 # exact angles: rounding only
    assert fenney.polar_bound(10) < 1.0                         # the 1-LSB target holds
    assert rsqrt_lut(12).max_error < 10                         # bin width 16 in n2
    assert rsqrt_lut(14).max_error < rsqrt_lut(12).max_error    # more address bits, less


@settings(max_examples=200)
@given(st.integers(-256, 255), st.integers(0, 255), st.integers(-256, 255),
       st.integers(-128, 127), st.integers(-128, 127), st.integers(-128, 127),
       st.integers(0, 255), st.booleans())
def test_dot_model_range(x, y, z, lx, ly, lz, h, normalize):
    inp = {k: np.array([v]) for k, v in dict(x=x, y=y, z=z, lx=lx, ly=ly, lz=lz, h=h).items()}
    v = fenney.dot_float(inp, normalize)[0]
    assert 0 <= v <= 1023 and np.isfinite(v)
    assert 0.5 < fenney.dot_bound(inp, normalize)[0] < 2
