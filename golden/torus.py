"""Quadratic vector interpolation of L' and H' (seed 000 §2) on a torus of 12 x 12 segments:
288 triangles, as in the seeds. At each vertex, L and H are rotated into the surface frame
(T, B, N); the mid-edge vectors are the normalised averages of the vertex vectors (the seed's
second construction); each component is interpolated quadratically with the ortho-normalised
setup (seed 001 eq 16). The length error of the interpolated vectors, |1 - ||L'|||, is
measured on a grid inside every triangle, beside linear interpolation's (seed 000 §3)."""
import numpy as np

from . import quadratic as q

__all__ = ["length_errors"]


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _frames(theta, phi):
    n = np.stack([np.cos(phi) * np.cos(theta), np.cos(phi) * np.sin(theta), np.sin(phi)], -1)
    t = np.stack([-np.sin(theta), np.cos(theta), np.zeros_like(theta)], -1)
    return t, np.cross(n, t), n


def length_errors(segments=12, light=(1.0, 1.0, 1.0), view=(0.0, 0.0, 1.0), grid=12):
    light, view = _unit(np.array(light)), _unit(np.array(view))
    vectors = {"L": light, "H": _unit(light + view)}
    k = np.arange(segments)
    i, j = np.meshgrid(k, k, indexing="ij")
    quads = np.stack([i.ravel(), j.ravel()], -1)
    tri_idx = []
    for a, b in quads:
        c00, c10, c01, c11 = (a, b), ((a + 1) % segments, b), (a, (b + 1) % segments), \
            ((a + 1) % segments, (b + 1) % segments)
        tri_idx += [(c00, c10, c11), (c00, c11, c01)]
    tri_idx = np.array(tri_idx)                                   # (288, 3, 2)
    ang = 2 * np.pi * tri_idx / segments
    T, B, N = _frames(ang[..., 0], ang[..., 1])
    # a grid of (u, v) inside the ortho-normalised triangle
    uu, vv = np.meshgrid(np.linspace(0, 1, grid + 1), np.linspace(0, 1, grid + 1))
    keep = uu + vv <= 1 + 1e-12
    u, v = uu[keep], vv[keep]
    out = {"triangles": len(tri_idx), "max_normal_angle_deg": 0.0}
    dots = [(N[:, a] * N[:, b]).sum(-1) for a, b in ((0, 1), (0, 2), (1, 2))]
    out["max_normal_angle_deg"] = float(np.degrees(np.arccos(np.clip(np.min(dots), -1, 1))))
    errs = {"quadratic": [], "linear": []}
    for vec in vectors.values():
        rot = np.stack([(T * vec).sum(-1), (B * vec).sum(-1), (N * vec).sum(-1)], -1)  # (288,3,3)
        mids = [_unit(rot[:, a] + rot[:, b]) for a, b in ((0, 1), (0, 2), (1, 2))]
        quad = np.zeros((len(rot), len(u), 3))
        lin = np.zeros_like(quad)
        for c in range(3):
            s = np.stack([rot[:, 0, c], rot[:, 1, c], rot[:, 2, c]] + [m[:, c] for m in mids], -1)
            quad[..., c] = q.eval_uv(q.ortho_uv(s)[:, None, :], u, v)
            lin[..., c] = q.eval_uv(q.linear_uv(rot[:, 0, c], rot[:, 1, c], rot[:, 2, c])[:, None, :], u, v)
        errs["quadratic"].append(np.abs(1 - np.linalg.norm(quad, axis=-1)).ravel())
        errs["linear"].append(np.abs(1 - np.linalg.norm(lin, axis=-1)).ravel())
    for name, e in errs.items():
        e = np.concatenate(e) * 100
        out[name] = {"mean": float(e.mean()), "max": float(e.max())}
    out["seed"] = {"mean": 0.45, "max": 3.2}
    return out


if __name__ == "__main__":
    print(length_errors())
