"""Collision handling of CASSI 3.0: the tongue is kept under the palate and in front of the
pharyngeal wall by a *soft* projection, and out of the front teeth by a projection onto their
surface (or, as the tongue heads out, into the gap between them, continuously).

Soft: a coordinate ``v`` bounded above by ``b`` becomes ``b - w * log(1 + exp((b - v) / w))``:
equal to ``v`` (within ``w * exp(-(b - v) / w)``) when it is clear of the bound, ``b`` when the
data puts it far past, and a smooth, monotonic function of ``v`` in between, so the constraint
adds no jitter to a smooth trajectory. Bounds already include the margin.
"""
from __future__ import annotations

import numpy as np

__all__ = ["soft_below", "soft_above", "PalateHeights", "FrontTeeth"]


def soft_below(v: np.ndarray, bound: np.ndarray, width: float) -> np.ndarray:
    """``v`` kept below ``bound`` (softly, see the module docstring); +inf bounds leave it."""
    b = np.where(np.isfinite(bound), bound, 0.0)
    out = b - width * np.logaddexp(0.0, (b - v) / width)
    return np.where(np.isfinite(bound), out, v)


def soft_above(v: np.ndarray, bound: np.ndarray, width: float) -> np.ndarray:
    """``v`` kept above ``bound`` (softly); -inf bounds leave it."""
    return -soft_below(-np.asarray(v), -np.asarray(bound), width)


class PalateHeights:
    """Height of the palate's lowest surface over (x, |y|), looked up bilinearly on a grid.

    Parameters
    ----------
    vertices : float (V, 3)
        The face with the palate placed (it does not move during a task).
    triangles : int (T, 3)
        The palate's triangles (0-based rows).
    step : float
        Grid spacing, Parke units.

    Behind the palate's back edge the bound rises one unit per unit (the soft palate is not
    modelled: the tongue is free there, and the bound grows continuously so nothing jumps);
    beside and in front of it the edge heights hold (the teeth are there).
    """

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray, step: float):
        p = np.asarray(vertices, np.float64)[np.asarray(triangles, np.int64)]     # (T, 3, 3)
        lo, hi = p[..., :2].reshape(-1, 2).min(0), p[..., :2].reshape(-1, 2).max(0)
        self.x0, self.step = float(lo[0]), float(step)
        xs = np.arange(lo[0], hi[0] + step, step)
        ys = np.arange(0.0, hi[1] + step, step)
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        z = _lowest_hit(np.stack([gx.ravel(), gy.ravel()], 1), p).reshape(gx.shape)
        # Outside the outline: hold the nearest height along y, then along x.
        for i in range(len(xs)):
            ok = np.isfinite(z[i])
            if ok.any():
                z[i] = np.interp(ys, ys[ok], z[i, ok])
        ok = np.isfinite(z).all(axis=1)
        for j in range(len(ys)):
            z[:, j] = np.interp(xs, xs[ok], z[ok, j])
        self.z = z
        self.x_back = float(xs[ok][0])

    def __call__(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Palate height over each point (any shape), Parke units."""
        nx, ny = self.z.shape
        fx = np.clip((x - self.x0) / self.step, 0.0, nx - 1.000001)
        fy = np.clip(np.abs(y) / self.step, 0.0, ny - 1.000001)
        ix, iy = fx.astype(np.int64), fy.astype(np.int64)
        tx, ty = fx - ix, fy - iy
        z = self.z
        h = ((z[ix, iy] * (1 - ty) + z[ix, iy + 1] * ty) * (1 - tx)
             + (z[ix + 1, iy] * (1 - ty) + z[ix + 1, iy + 1] * ty) * tx)
        return h + np.maximum(self.x_back - x, 0.0)


def _lowest_hit(q: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Lowest z of the triangles ``tri`` (T, 3, 3) above each (x, y) of ``q`` (G, 2); NaN where
    none covers it."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    d = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    keep = np.abs(d) > 1e-12
    a, b, c, d = a[keep], b[keep], c[keep], d[keep]
    qx, qy = q[:, 0, None], q[:, 1, None]
    l1 = ((b[:, 1] - c[:, 1]) * (qx - c[:, 0]) + (c[:, 0] - b[:, 0]) * (qy - c[:, 1])) / d
    l2 = ((c[:, 1] - a[:, 1]) * (qx - c[:, 0]) + (a[:, 0] - c[:, 0]) * (qy - c[:, 1])) / d
    l3 = 1.0 - l1 - l2
    eps = -1e-9
    inside = (l1 >= eps) & (l2 >= eps) & (l3 >= eps)
    z = l1 * a[:, 2] + l2 * b[:, 2] + l3 * c[:, 2]
    z = np.where(inside, z, np.inf).min(axis=1)
    return np.where(np.isfinite(z), z, np.nan)


class FrontTeeth:
    """The quads at the front of the upper and the lower arch, that the tongue may not pass
    through (it may pass *between* them: a protruded tongue goes through the gap of the open
    jaw, as in the XRMB protocol's tongue protrusion, task 118).

    Parameters
    ----------
    upper, lower : int (Q, 2, 2)
        Per quad its mesial and distal edge, each as (tip row, gum row), 0-based.
    """

    def __init__(self, upper: np.ndarray, lower: np.ndarray):
        self.upper = np.asarray(upper, np.int64).reshape(-1, 2, 2)
        self.lower = np.asarray(lower, np.int64).reshape(-1, 2, 2)

    @staticmethod
    def front_edges(vertices: np.ndarray, quads, *, min_nx: float) -> np.ndarray:
        """The (mesial, distal) x (tip, gum) rows of the quads whose outward normal is at least
        ``min_nx`` forward. ``quads``: (tip-mesial, tip-distal, gum-distal, gum-mesial) 1-based
        numbers each."""
        v = np.asarray(vertices, np.float64)
        keep = []
        for q in quads:
            tm, td, gd, gm = (int(n) - 1 for n in q)
            dx, dy = v[td, 0] - v[tm, 0], abs(v[td, 1]) - abs(v[tm, 1])
            length = np.hypot(dx, dy)
            if length > 0 and abs(dy) >= min_nx * length:
                keep.append(((tm, gm), (td, gd)))
        return np.asarray(keep, np.int64).reshape(-1, 2, 2)

    def keep_out(self, positions: np.ndarray, p: np.ndarray, margin: float, *,
                 toward_gap: np.ndarray, release: np.ndarray) -> np.ndarray:
        """Keep the points out of the front teeth.

        A point in front of a front tooth's surface (within ``margin``; the surface extended up
        and down, so no edge between two points can cross it) moves toward the gap between the
        upper and the lower teeth's tips by the frame's ``toward_gap`` weight (0: the tongue
        stays in the mouth; 1: it is on its way out), then back behind the surface, except by
        up to the frame's ``release`` where it is at the gap's height (below the upper tooth's
        tip and above the lower's). So a point is in front of a tooth only between their tips,
        and everything changes continuously with the weights; where the gap is shut no point
        is between the tips, and every point is behind one of the two surfaces.

        Parameters
        ----------
        positions : float (F, V, 3)
            Teeth placed for each frame.
        p : float (F, E, 3)
            The points (left half), changed in place and returned.
        margin : float
            Parke units; it also closes the slits between neighbouring teeth.
        toward_gap : float (F,) in [0, 1]
        release : float (F,) >= 0
            Parke units.

        Returns
        -------
        p
        """
        # Only points that may be in front of a wall (most are well behind the teeth): a
        # point at or behind every quad's lowest possible x, less the margin, stays as it is.
        y = np.abs(p[..., 1])
        lowest = np.minimum(_lowest_wall(positions, self.upper, y, margin),
                            _lowest_wall(positions, self.lower, y, margin))
        fi, ei = np.nonzero(p[..., 0] > lowest - margin)
        if len(fi) == 0:
            return p
        p[fi, ei] = self._keep_out(positions, p[fi, ei], fi, margin, toward_gap[fi],
                                   release[fi])
        return p

    def _keep_out(self, positions, p, frames, margin, toward_gap, release):
        """:meth:`keep_out` for points (P, 3) of the frames ``frames`` (P,); returns them."""
        y = np.abs(p[:, 1])
        wu, tu = _wall(positions, self.upper, frames, y, p[:, 2], margin)
        wl, tl = _wall(positions, self.lower, frames, y, p[:, 2], margin)
        # the gap's ends; a set that does not span |y| leaves that end open
        lo = np.where(np.isnan(tl), -np.inf, tl + margin)
        hi = np.where(np.isnan(tu), np.inf, tu - margin)
        x, z = p[:, 0], p[:, 2]
        # down from the upper teeth's height in front of the upper teeth, up from the lower's
        # in front of the lower teeth (each set's own surface: the jaw moves the lower one)
        target = np.where((x > wu - margin) & (z > hi), hi,
                          np.where((x > wl - margin) & (z < lo), lo, z))
        z = z + toward_gap * (target - z)
        # let forward only at the gap's height (within the margin: below a tooth's tip)
        up = np.clip(1.0 - (z - hi) / margin, 0.0, 1.0)
        down = np.clip(1.0 - (lo - z) / margin, 0.0, 1.0)
        x = np.minimum(x, wu - margin + release * up)
        p[:, 0] = np.minimum(x, wl - margin + release * down)
        p[:, 2] = z
        return p


def _lowest_wall(positions: np.ndarray, edges: np.ndarray, y: np.ndarray, slit: float
                 ) -> np.ndarray:
    """A lower bound of the x :func:`_wall` gives points (F, E) at ``y`` = |y|, from each
    quad's corners: its x is interpolated between its two edges, and extrapolated beyond them
    by at most ``slit`` in |y| (x spread * slit / |y| gap; no bound where the edges may meet in
    |y|); only quads whose |y| range (widened by ``slit``) holds the point count. +inf where
    none does."""
    out = np.full(np.shape(y), np.inf)
    for quad in edges:
        v = np.asarray(positions[:, quad.reshape(-1)], np.float64).reshape(-1, 2, 2, 3)
        x, ay = v[..., 0], np.abs(v[..., 1])                          # (F, 2 edges, 2)
        same = np.sign(v[..., 0, 1]) * np.sign(v[..., 1, 1]) >= 0
        ylo, yhi = np.where(same, ay.min(-1), 0.0), ay.max(-1)         # (F, 2 edges)
        xlo, xhi = x.min(-1), x.max(-1)
        spread = np.maximum(xhi[:, 1] - xlo[:, 0], xhi[:, 0] - xlo[:, 1])
        gap = np.maximum(np.maximum(ylo[:, 1] - yhi[:, 0], ylo[:, 0] - yhi[:, 1]), 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            reach = np.where(gap > 0.0, spread * slit / gap, np.inf)
        bound = (xlo.min(-1) - reach)[:, None]
        inside = (y >= ylo.min(-1)[:, None] - slit) & (y <= yhi.max(-1)[:, None] + slit)
        out = np.where(inside & (bound < out), bound, out)
    return out


def _wall(positions: np.ndarray, edges: np.ndarray, frames: np.ndarray, y: np.ndarray,
          z: np.ndarray, slit: float) -> tuple[np.ndarray, np.ndarray]:
    """For points (P,) of the frames ``frames``: x of the front-most quad of ``edges`` at
    (|y|, z) (each edge extended vertically) and the z of that quad's tip at |y|; +inf / NaN
    where none spans |y|. Each quad's span is widened by ``slit`` on both sides, so that the
    slits between neighbouring teeth (0.8 Parke units each side in the generated face) are no
    way through.

    One quad at a time, keeping the front-most so far: the few front quads (3 per arch) make
    the loop short, and (points, quads, 2) temporaries would not stay in cache."""
    shape = np.shape(y)
    wall, tipz = np.full(shape, np.inf), np.full(shape, np.nan)
    for quad in edges:
        ends = []
        for tip_row, gum_row in quad:
            tip = np.asarray(positions[frames, tip_row], np.float64)           # (P, 3)
            gum = np.asarray(positions[frames, gum_row], np.float64)
            d = gum - tip
            dz = d[:, 2]
            t = np.clip((z - tip[:, 2]) / np.where(np.abs(dz) > 1e-12, dz, 1.0), 0.0, 1.0)
            ends.append((tip[:, 0] + t * d[:, 0], np.abs(tip[:, 1] + t * d[:, 1]), tip[:, 2]))
        (x0, y0, z0), (x1, y1, z1) = ends
        span = (y >= np.minimum(y0, y1) - slit) & (y <= np.maximum(y0, y1) + slit)
        dy = y1 - y0
        s = (y - y0) / np.where(np.abs(dy) > 1e-12, dy, 1.0)
        x = np.where(span, x0 + s * (x1 - x0), np.inf)
        ahead = x < wall            # strict: on a tie the earlier quad stays, as argmin would
        wall = np.where(ahead, x, wall)
        tipz = np.where(ahead, z0 + s * (z1 - z0), tipz)
    return wall, np.where(np.isfinite(wall), tipz, np.nan)
