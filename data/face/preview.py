"""Matplotlib previews of the face (for debugging; the renderer makes the real images).

``preview_png(face, path)`` draws the mirrored head from the front, the side, three-quarters and
the half-face cut, flat-shaded with the polygon edges on top, plus the mouth parts (teeth,
tongue, palate) from the side and from below. Faces seen from behind are drawn dark (a wrong
winding stands out), except in the half view, which looks into the head and is two-sided. ``python -m cassi.data.face.preview OUT.png`` writes the neutral face.
"""
from __future__ import annotations

import sys
from os import PathLike

import numpy as np

from cassi.common.atomic import replacing
from cassi.data.face.model import build_face
from cassi.data.face.topology import render_topology

_COLOURS = {
    "skin": (0.86, 0.68, 0.58), "lips": (0.75, 0.35, 0.35), "eyelash": (0.15, 0.1, 0.1),
    "eyebrow": (0.3, 0.2, 0.15), "teeth_upper": (0.95, 0.94, 0.85),
    "teeth_lower": (0.90, 0.89, 0.80), "tongue": (0.85, 0.35, 0.4),
    "palate": (0.9, 0.55, 0.55), "eye_white": (0.95, 0.95, 0.93), "iris": (0.25, 0.4, 0.6),
    "fringe": (0.1, 0.15, 0.2), "pupil": (0.02, 0.02, 0.02), "reflection": (1.0, 1.0, 1.0),
}

#: The render parts of the teeth (cassi.data.face.topology splits the face's teeth in two).
_TEETH = ("teeth_upper", "teeth_lower")

#: name -> (elevation, azimuth) for matplotlib's view_init, Parke axes (X forward, Z up).
VIEWS = {"front": (5, 0), "side": (5, 90), "three-quarter": (15, 40), "half": (5, -90),
         "below": (-60, 20)}


def _draw(ax, topo, positions, *, parts=None, title="", view=(5, 0), edges=True,
          centre=None, span=None, two_sided=False):
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    v, tri, part = topo.mesh(positions)
    names = list(topo.parts)
    keep = np.ones(len(tri), bool) if parts is None else np.isin(
        part, [names.index(p) for p in parts if p in names])
    tri, part = tri[keep], part[keep]
    p = v[tri]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    elev, azim = np.radians(view[0]), np.radians(view[1])
    eye = np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
    light = eye + np.array([0.0, 0.3, 0.6])
    light /= np.linalg.norm(light)
    back = (n @ eye) < 0
    lit = np.where(back, -1.0, 1.0) * (n @ light) if two_sided else n @ light
    shade = 0.35 + 0.65 * np.clip(lit, 0.0, 1.0)
    base = np.array([_COLOURS.get(names[i], (0.6, 0.6, 0.6)) for i in part])
    col = base * shade[:, None]
    if not two_sided:
        # back faces (pointing away from the viewer) drawn dark so wrong windings stand out
        col[back] = col[back] * 0.25
    pc = Poly3DCollection(p, facecolors=col, edgecolors=(0, 0, 0, 0.25) if edges else col,
                          linewidths=0.2)
    ax.add_collection3d(pc)
    used = v[np.unique(tri)] if len(tri) else v
    lo, hi = used.min(axis=0), used.max(axis=0)
    mid = (lo + hi) / 2 if centre is None else np.asarray(centre, float)
    span = (hi - lo).max() / 2 if span is None else float(span)
    ax.set_xlim(mid[0] - span, mid[0] + span)
    ax.set_ylim(mid[1] - span, mid[1] + span)
    ax.set_zlim(mid[2] - span, mid[2] + span)
    ax.set_box_aspect((1, 1, 1), zoom=1.35)
    ax.view_init(elev=view[0], azim=view[1])
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)


def preview_png(face, path: str | PathLike, *, positions=None, dpi: int = 110,
                zoom_mouth: bool = True) -> None:
    """Write a PNG preview (front, side, three-quarter, half cut, mouth parts) atomically."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    pos = face.vertices if positions is None else np.asarray(positions)
    full = render_topology(face)
    half = render_topology(face, half=True)
    fig = plt.figure(figsize=(15, 9))
    panels = [
        (full, None, "front", VIEWS["front"]), (full, None, "side (left)", VIEWS["side"]),
        (full, None, "three-quarter", VIEWS["three-quarter"]),
        (half, None, "half (from the cut)", VIEWS["half"]),
        (full, [*_TEETH, "tongue", "palate", "lips"], "mouth parts, side", (5, 80)),
        (full, [*_TEETH, "tongue", "palate"], "mouth parts, from below", (-70, 10)),
    ]
    for k, (topo, parts, title, view) in enumerate(panels):
        ax = fig.add_subplot(2, 3, k + 1, projection="3d")
        # the cut shows the inside of the head: shade it two-sided like the renderer
        _draw(ax, topo, pos, parts=parts, title=title, view=view, two_sided=topo.half)
    fig.tight_layout()
    try:
        with replacing(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png")
    finally:
        plt.close(fig)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = argv[0] if argv else "face_preview.png"
    preview_png(build_face(), out)
    print(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
