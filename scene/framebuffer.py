"""The framebuffer's model: the depth test, the frame, the board's storage formats, and the
reference picture (``reference``: per-pixel Phong in float64, ``reference.png``).

One implementation serves the renderer (``scene/models.py``: the model and ideal pictures,
in float) and the board (``board/framebuffer.py``'s RTL, in raw integers and
RGB565): ``framebuffer`` is the depth test; ``board_frame`` is what the board's planes hold
after it; ``screen`` is what its scan-out shows.
"""
import numpy as np

from golden import bump as bumps, raster as raster_model, shade

__all__ = ["framebuffer", "reference", "rgb565", "expand565", "board_frame", "screen", "CLEAR"]

CLEAR = -(1 << 15)            # the board's cleared depth: the least s16


def framebuffer(size, x, y, depth, rgb, background):
    """The depth test and the frame: the largest depth wins, the earlier fragment on a tie
    (fragments in stream order). Returns (image uint8 (H, W, 3), covered (H, W) bool)."""
    W, H = size
    x, y, depth = map(np.asarray, (x, y, depth))
    ok = (x < W) & (y < H)
    order = np.flatnonzero(ok)
    pix = y[order] * W + x[order]
    best = np.lexsort((order, -depth[order], pix))
    first = np.ones(len(best), bool)
    first[1:] = pix[best][1:] != pix[best][:-1]
    win = order[best[first]]
    img = np.empty((H, W, 3), np.uint8)
    img[:] = np.rint(np.array(background) * 255).astype(np.uint8)
    cov = np.zeros((H, W), bool)
    img[y[win], x[win]] = rgb[win]
    cov[y[win], x[win]] = True
    return img, cov


def rgb565(rgb):
    """8-bit (..., 3) to RGB565 words: each channel's top bits."""
    rgb = np.asarray(rgb, np.int64)
    return (rgb[..., 0] >> 3) << 11 | (rgb[..., 1] >> 2) << 5 | rgb[..., 2] >> 3


def expand565(word):
    """RGB565 words to 8-bit (..., 3), the top bits repeated below (31 -> 255)."""
    w = np.asarray(word, np.int64)
    r, g, b = (w >> 11) & 31, (w >> 5) & 63, w & 31
    return np.stack([(r << 3) | (r >> 2), (g << 2) | (g >> 4), (b << 3) | (b >> 2)],
                    -1).astype(np.uint8)


def board_frame(size, frag, background):
    """What the board's colour plane holds after the RTL's fragments ``frag`` (raw x, y,
    depth, r, g, b): the same depth test on the raw depth, clamped above the clear as the
    RTL clamps it; the colours as RGB565, widened back to 8 bits."""
    depth = np.maximum(np.asarray(frag["depth"], np.int64), CLEAR + 1)
    rgb = expand565(rgb565(np.stack([frag[c] for c in "rgb"], -1)))
    back = expand565(rgb565(np.rint(np.array(background) * 255).astype(np.int64)))
    img, _ = framebuffer(size, frag["x"], frag["y"], depth, rgb, back / 255)
    return img


def screen(img, factor, x0, y0, width=640, height=480):
    """The picture on a ``width x height`` screen: ``img`` scaled by ``factor`` at (x0, y0),
    black around it."""
    out = np.zeros((height, width, 3), np.uint8)
    big = np.repeat(np.repeat(img, factor, 0), factor, 1)
    out[y0:y0 + big.shape[0], x0:x0 + big.shape[1]] = big
    return out


def reference(prep):
    """Per-pixel Phong in float64, exact power: each covered pixel's normal interpolated
    (affine in screen space) from the exact vertex normals at the exact projected vertices,
    normalised; the same coverage and the depth test on the exact 1/z."""
    scene, q, fl = prep["scene"], prep["params"], prep["float"]
    x = np.stack([prep["inputs"][f"x{c}"] for c in range(3)], -1)
    y = np.stack([prep["inputs"][f"y{c}"] for c in range(3)], -1)
    tri, px, py = raster_model.coverage(x, y, q["sub_bits"], q["screen_bits"])
    sx, sy = fl["sx"][tri], fl["sy"][tri]
    cx, cy = px + 0.5, py + 0.5
    det = (sx[:, 1] - sx[:, 0]) * (sy[:, 2] - sy[:, 0]) - (sx[:, 2] - sx[:, 0]) * (sy[:, 1] - sy[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        b1 = ((cx - sx[:, 0]) * (sy[:, 2] - sy[:, 0]) - (sx[:, 2] - sx[:, 0]) * (cy - sy[:, 0])) / det
        b2 = ((sx[:, 1] - sx[:, 0]) * (cy - sy[:, 0]) - (cx - sx[:, 0]) * (sy[:, 1] - sy[:, 0])) / det
    w = np.stack([1 - b1 - b2, b1, b2], -1)
    n = (w[..., None] * fl["N"][tri]).sum(1)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    b = prep["bump"]
    if b:     # the texel's exact normal, in the pixel's interpolated tangent frame
        st = (w[..., None] * b["st"][tri]).sum(1)
        nt = bumps.sample(b["normals"], st, b["filter"])
        T, B = ((w[..., None] * f[tri]).sum(1) for f in b["frames"][:2])
        T = T - np.einsum("ij,ij->i", T, n)[:, None] * n
        T = T / np.linalg.norm(T, axis=-1, keepdims=True)
        B = np.cross(n, T)
        n = nt[:, :1] * T + nt[:, 1:2] * B + nt[:, 2:] * n
    d = [n @ L for L in fl["L"]]
    p = [np.maximum(0, n @ Hv) ** scene["material"]["shininess"] if q["specular"]
         else np.zeros(len(tri)) for Hv in fl["H"]]
    rgb = shade.colour_float(scene, d, p)
    depth = (w * fl["inv_z"][tri]).sum(1)
    return framebuffer(prep["size"], px, py, depth, rgb, scene["image"]["background"])[:2]
