"""Seed 003's rotation and illumination models (golden/rotation.py), no RTL involved.

The exact rotation is held to geometry; the published method to the equations worked by hand,
to exactness where the method is exact (D = 0 or 180 deg, theta_A = 0), and to finite, in-range
results on every hard case it leaves open."""
import numpy as np
from hypothesis import example, given, strategies as st

from golden import angular as rot

DEG = np.pi / 180


def test_exact_rotation_takes_n_to_the_pole_and_keeps_angles():
    rng = np.random.default_rng(0)
    pn, tn = rot.random_hemisphere(rng, 1000)
    pa, ta = rot.random_hemisphere(rng, 1000)
    assert np.allclose(rot.rotate_exact(pn, tn, pn, tn)[1], 0, atol=1e-6)
    _, t_rot = rot.rotate_exact(pn, tn, pa, ta)
    cos_sep = (rot.to_vector(pn, tn) * rot.to_vector(pa, ta)).sum(-1)
    assert np.allclose(np.cos(t_rot), cos_sep, atol=1e-12)       # N'.A' = N.A
    # a hand case: N = x axis, A = y axis -> A stays the y axis
    p, t = rot.rotate_exact(0.0, 90 * DEG, 90 * DEG, 90 * DEG)
    assert np.allclose([p, t], [90 * DEG, 90 * DEG])


def test_law_of_cosines_is_exact():
    rng = np.random.default_rng(1)
    pa, pn = rng.uniform(0, 2 * np.pi, (2, 5000))
    ta, tn = rng.uniform(0, np.pi, (2, 5000))                     # theta sums past 180 deg
    got = rot.inner_product(pa, ta, pn, tn)
    want = (rot.to_vector(pa, ta) * rot.to_vector(pn, tn)).sum(-1)
    assert np.allclose(got, want, atol=1e-12)
    assert got.min() < -0.9                                       # negatives included


def test_paper_method_by_hand():
    """theta_N = 0, theta_A = 45, D = 45 deg: theta_x = asin(sin 45 cos 45) = 30 deg,
    yk = sin 45 sin 45 / cos 30 = 0.57735, acos = 54.7356 deg, theta_prop = 0.391827,
    theta' = 30 + 60 * 0.391827 = 53.5096 deg (exact: 45); phi' = atan(0.5 / 0.5) = 45."""
    p, t = rot.rotate_paper(0.0, 0.0, 45 * DEG, 45 * DEG)
    assert abs(p / DEG - 45) < 1e-9 and abs(t / DEG - 53.5096) < 1e-3


def test_paper_method_exact_where_the_vector_has_no_y():
    rng = np.random.default_rng(2)
    pn = rng.uniform(0, 2 * np.pi, 2000)
    tn, ta = rng.uniform(0, np.pi / 2, (2, 2000))
    for d in (0.0, np.pi):                                        # D = 0 and 180 deg
        ex = rot.to_vector(*rot.rotate_exact(pn, tn, pn + d, ta))
        pp = rot.to_vector(*rot.rotate_paper(pn, tn, pn + d, ta))
        assert np.abs(ex - pp).max() < 1e-9
    ex = rot.to_vector(*rot.rotate_exact(pn, tn, pn * 0.3, 0 * ta))   # theta_A = 0
    pp = rot.to_vector(*rot.rotate_paper(pn, tn, pn * 0.3, 0 * ta))
    assert np.abs(ex - pp).max() < 1e-9


def test_theta_n_zero_phi_exact_theta_is_the_proportion_rule():
    rng = np.random.default_rng(3)
    pa, pn = rng.uniform(0, 2 * np.pi, (2, 5000))
    ta = rng.uniform(0, np.pi / 2, 5000)
    p, t = rot.rotate_paper(pn, 0.0, pa, ta)
    p_ex, t_ex = rot.rotate_exact(pn, 0.0, pa, ta)
    wrap = np.angle(np.exp(1j * (p - p_ex)))
    assert np.abs(wrap[ta > 1e-6]).max() < 1e-9                  # phi' exact
    # theta' is the rule's estimate: never below the truth, and off by up to ~9 deg
    assert np.all(t >= t_ex - 1e-9)
    assert 5 * DEG < np.abs(t - t_ex).max() < 12 * DEG


def test_method_error_grows_with_separation():
    rows, _, _ = rot.method_error(20_000)
    means = [r[3] for r in rows]
    assert all(a < b for a, b in zip(means, means[1:]))
    assert rows[0][3] < 5                                          # < 15 deg apart: mean < 5 deg


angles = st.floats(-4 * np.pi, 4 * np.pi, allow_nan=False)
polar = st.floats(0, np.pi, allow_nan=False)


@given(angles, polar, angles, polar)
@example(2.220446049250313e-16, 0.0, 0.0, 1.0)     # phi' was 2 pi itself (np.mod of -tiny)
def test_paper_method_always_finite_and_in_range(phi_n, theta_n, phi_a, theta_a):
    p, t = rot.rotate_paper(phi_n, theta_n, phi_a, theta_a)
    assert np.isfinite(p) and np.isfinite(t)
    assert 0 <= p < 2 * np.pi and 0 <= t <= np.pi


def test_paper_method_hard_cases():
    cases = [  # (phi_n, theta_n, phi_a, theta_a): the cases the paper leaves open
        (0, 30, 0, 30),        # sin Z = 0 with a zero numerator: A = N
        (0, 30, 90, 30),       # theta_x = 0 -> Z = -30, negative
        (0, 60, 90, 60),       # sin Z != 0, yk large
        (0, 0, 90, 90),        # cos Z = 1, yk = 1: asin at 1
        (0, 90, 0, 0),         # Z = -90: cos Z = 0, |yk| >= 1 guarded
        (0, 90, 180, 90),      # theta_x = -90, Z = -180: sums past 180 deg
        (359, 10, 1, 10),      # phi wrapping at 0/360
        (0, 45, 0, 0),         # theta_A = 0
    ]
    for pn, tn, pa, ta in cases:
        p, t = rot.rotate_paper(pn * DEG, tn * DEG, pa * DEG, ta * DEG)
        assert np.isfinite(p) and np.isfinite(t) and 0 <= t <= np.pi
    p, t = rot.rotate_paper(0, 30 * DEG, 90 * DEG, 30 * DEG)
    assert 90 < p / DEG < 270                                      # -x side of N
